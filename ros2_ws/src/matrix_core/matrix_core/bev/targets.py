"""Training targets on the BEV grid from ground-truth positions.

Convention: see ``heads.py`` (offsets in metres, world x/y). A person belongs to the cell containing
its position; people outside the grid are left out.
"""

import numpy as np

from matrix_core.geometry.grid import BevGrid


def bev_targets(grid: BevGrid, positions: dict, previous: dict = None, sigma_m: float = 0.3) -> dict:
    """Heatmap, offset and tracking-offset targets of one frame.

    Args:
        grid: the BEV grid.
        positions: person id -> (2,) world metres in this frame.
        previous: person id -> (2,) world metres in the previous frame (None: no tracking targets).
        sigma_m: std of the Gaussian bump (metres).

    Returns:
        dict of float32 arrays: ``heatmap`` (1, R, Q) in [0, 1] with exactly 1 at each person's cell;
        ``offset`` (2, R, Q) and ``tracking`` (2, R, Q) metres at those cells; ``center_mask`` (1, R, Q)
        1 at the people's cells; ``tracking_mask`` (1, R, Q) 1 where a tracking target exists.
    """
    rows, cols = grid.shape
    heat = np.zeros((rows, cols), np.float32)
    offset = np.zeros((2, rows, cols), np.float32)
    tracking = np.zeros((2, rows, cols), np.float32)
    center = np.zeros((1, rows, cols), np.float32)
    track_mask = np.zeros((1, rows, cols), np.float32)
    ids = [i for i in positions if grid.contains(np.asarray(positions[i])[:2])[0]]
    if ids:
        xy = np.array([np.asarray(positions[i], dtype=np.float64)[:2] for i in ids])
        cells = np.floor(grid.world_to_cell(xy) + 0.5).astype(int)  # (col, row) of the containing cell
        cells[:, 0] = np.clip(cells[:, 0], 0, cols - 1)
        cells[:, 1] = np.clip(cells[:, 1], 0, rows - 1)
        centres = grid.cell_to_world(cells.astype(float))
        rr, cc = np.mgrid[0:rows, 0:cols]
        radius = int(np.ceil(3 * sigma_m / grid.cell))
        for k, (c, r) in enumerate(cells):
            r0, r1, c0, c1 = (
                max(r - radius, 0),
                min(r + radius + 1, rows),
                max(c - radius, 0),
                min(c + radius + 1, cols),
            )
            d2 = (
                ((grid.cell_to_world(np.stack([cc[r0:r1, c0:c1].ravel(), rr[r0:r1, c0:c1].ravel()], 1)) - xy[k]) ** 2)
                .sum(1)
                .reshape(r1 - r0, c1 - c0)
            )
            bump = np.exp(-d2 / (2 * sigma_m**2)).astype(np.float32)
            heat[r0:r1, c0:c1] = np.maximum(heat[r0:r1, c0:c1], bump)
        for k, (c, r) in enumerate(cells):
            heat[r, c] = 1.0
            center[0, r, c] = 1.0
            offset[:, r, c] = xy[k] - centres[k]
            if previous is not None and ids[k] in previous:
                tracking[:, r, c] = np.asarray(previous[ids[k]], dtype=np.float64)[:2] - xy[k]
                track_mask[0, r, c] = 1.0
    return {
        'heatmap': heat[None],
        'offset': offset,
        'tracking': tracking,
        'center_mask': center,
        'tracking_mask': track_mask,
    }
