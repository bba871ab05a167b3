"""Line of sight: rays from a camera centre to points, tested against the scene's boxes, and image bounds.

Convention: internal world metres; boxes are ((x0, y0, x1, y1), height) standing on z = 0.
"""

import numpy as np

from matrix_core.geometry.occlusion import segments_blocked


def rays_blocked(origin, targets, boxes) -> np.ndarray:
    """(N,) bool: whether the segment from ``origin`` (3,) to each of ``targets`` (N, 3) passes through any
    of the ``boxes`` (this module's ((x0, y0, x1, y1), height) form); see
    :func:`~matrix_core.geometry.occlusion.segments_blocked`."""
    return segments_blocked(origin, targets, [(*bounds, h) for bounds, h in boxes])


def line_of_sight(camera, positions, boxes, sample_heights=(0.05, 0.9), margin_m: float = 0.05) -> np.ndarray:
    """(N,) bool: which persons standing at ``positions`` (N, 2) the camera sees.

    A person is visible when its foot point projects inside the image and the rays from the CURRENT camera
    centre to its axis at every height in ``sample_heights`` are not blocked by any box (block, pillars,
    distractors, buildings) grown by ``margin_m`` sideways (a ray grazing an edge within a few centimetres
    would put the person's rendered foot pixel on the occluder). Other persons do not count as occluders
    (as in MATRIX's LoS files).
    """
    boxes = [((x0 - margin_m, y0 - margin_m, x1 + margin_m, y1 + margin_m), h) for (x0, y0, x1, y1), h in boxes]
    positions = np.asarray(positions, dtype=float).reshape(-1, 2)
    n = len(positions)
    if n == 0:
        return np.zeros(0, dtype=bool)
    foot = np.concatenate([positions, np.zeros((n, 1))], axis=1)
    uv = camera.project(foot)
    visible = np.isfinite(uv).all(axis=1) & camera.in_image(np.nan_to_num(uv, nan=-1e9))
    for z in sample_heights:
        pts = np.concatenate([positions, np.full((n, 1), z)], axis=1)
        visible &= ~rays_blocked(camera.center, pts, boxes)
    return visible
