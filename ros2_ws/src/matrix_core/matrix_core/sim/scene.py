"""The static world of one scene variant: ground texture pyramid, occluding boxes, building facades and
checkerboards (with their true inner-corner positions).

Convention: internal world metres. Facade quads are (4, 3) corners ordered top-left, top-right,
bottom-right, bottom-left as seen from INSIDE the square (their texture row 0 is the top).
"""

import dataclasses
from dataclasses import dataclass

import numpy as np

from matrix_core.sim.distractors import Distractors
from matrix_core.sim.textures import (
    facade_style,
    facade_texture,
    ground_style,
    ground_texture,
    styled_facade_texture,
    tex_H_ground,
    texture_pyramid,
)

# Marker id of board b's inner corner (i, j), i = 1..nx-1, j = 1..ny-1 (nx, ny squares along x, y):
# 1000 * (b + 1) + (j - 1) * (nx - 1) + (i - 1).
BOARD_MARKER_BASE = 1000


@dataclass
class Facade:
    corners: np.ndarray  # (4, 3) metres: top-left, top-right, bottom-right, bottom-left (seen from inside)
    texture: np.ndarray  # (rows, cols, 3) BGR, row 0 at the top edge

    def world_from_tex(self) -> np.ndarray:
        """(4, 3) affine map from homogeneous texture pixels (col, row, 1) to world points (x, y, z, 1)."""
        rows, cols = self.texture.shape[:2]
        tl, tr, _, bl = self.corners
        out = np.zeros((4, 3))
        out[:3, 0] = (tr - tl) / cols
        out[:3, 1] = (bl - tl) / rows
        out[:3, 2] = tl
        out[3, 2] = 1.0
        return out


def board_corners(board, index: int) -> tuple:
    """Inner corners of a board: ((M,) marker ids, (M, 3) world metres), i along x fastest."""
    nx, ny = board.squares_xy
    ii, jj = np.meshgrid(np.arange(1, nx), np.arange(1, ny))
    ids = BOARD_MARKER_BASE * (index + 1) + (jj - 1) * (nx - 1) + (ii - 1)
    xyz = np.stack(
        [board.origin[0] + ii * board.square_m, board.origin[1] + jj * board.square_m, np.full(ii.shape, board.z)],
        axis=-1,
    )
    return ids.reshape(-1), xyz.reshape(-1, 3)


def box_faces(bounds, height: float) -> list:
    """The 5 visible faces (4 sides, top) of a box as ((4, 3) corners, (3,) outward normal)."""
    x0, y0, x1, y1 = bounds
    b = [[x0, y0, 0], [x1, y0, 0], [x1, y1, 0], [x0, y1, 0]]
    t = [[x, y, height] for x, y, _ in b]
    faces = [
        ([b[0], b[1], t[1], t[0]], [0, -1, 0]),
        ([b[1], b[2], t[2], t[1]], [1, 0, 0]),
        ([b[2], b[3], t[3], t[2]], [0, 1, 0]),
        ([b[3], b[0], t[0], t[3]], [-1, 0, 0]),
        (t, [0, 0, 1]),
    ]
    return [(np.array(c, dtype=float), np.array(n, dtype=float)) for c, n in faces]


class Scene:
    """Static geometry and textures of ``config``, built once per sequence.

    Args:
        config: :class:`~matrix_core.sim.config.SceneConfig`.
        rng: generator for textures and building layout.
        m_per_px: ground texture resolution (metres per texel at pyramid level 0).
        variety_rng: generator of the per-sequence randomisation (``config.distractors``: distractor
            objects, ground materials, facade styles); None for the plain scene.
    """

    def __init__(self, config, rng: np.random.Generator, m_per_px: float, variety_rng: np.random.Generator = None):
        self.config = config
        cx, cy = config.center
        r = config.building_distance + 2.0
        self.extent = (cx - r, cy - r, cx + r, cy + r)
        self.m_per_px = m_per_px
        dcfg = config.distractors if variety_rng is not None else None
        on = dcfg is not None and dcfg.enabled
        # Separate streams, so that e.g. changing the distractor counts keeps the ground and the facades.
        place_rng, ground_rng, facade_rng = variety_rng.spawn(3) if variety_rng is not None else (None,) * 3
        self.distractors = Distractors(config, place_rng)
        g_style = ground_style(ground_rng, config) if on and dcfg.ground_variety else None
        self.facade_style = facade_style(facade_rng) if on and dcfg.facade_variety else None
        base = ground_texture(config, self.extent, m_per_px, rng, g_style)
        self.ground_levels = [
            (img, tex_H_ground(self.extent, m_per_px * 2**k)) for k, img in enumerate(texture_pyramid(base, 4))
        ]
        self.boxes = [(b.bounds, b.height, b) for b in list(config.obstacles) + self.distractors.boxes]
        self.rounds = self.distractors.rounds  # vertical distractors (poles, posts, trees...), see distractors.py
        self.facades, self.building_boxes = self._buildings(rng)
        self.boards = list(config.boards)
        ids, xyz = zip(*(board_corners(b, k) for k, b in enumerate(self.boards))) if self.boards else ((), ())
        self.marker_ids = np.concatenate(ids) if ids else np.zeros(0, dtype=np.int64)
        self.marker_xyz = np.concatenate(xyz) if xyz else np.zeros((0, 3))

    def _buildings(self, rng) -> tuple:
        """Facades on a square ring at ``building_distance`` (each side split into buildings of random width
        and height), and the (bounds, height) boxes behind them for line-of-sight tests."""
        cx, cy = self.config.center
        d = self.config.building_distance
        lo, hi = self.config.building_height
        facades, boxes = [], []
        # Walk each side so that the facade faces the centre: (start corner, direction, inward normal).
        sides = [
            ((cx - d, cy + d), (1, 0), (0, -1)),
            ((cx + d, cy + d), (0, -1), (-1, 0)),
            ((cx + d, cy - d), (-1, 0), (0, 1)),
            ((cx - d, cy - d), (0, 1), (1, 0)),
        ]
        for start, direction, inward in sides:
            start, direction, inward = (np.array(v, dtype=float) for v in (start, direction, inward))
            s = 0.0
            while s < 2 * d - 1e-6:
                w = min(float(rng.uniform(10.0, 22.0)), 2 * d - s)
                h = float(rng.uniform(lo, hi))
                a, b = start + direction * s, start + direction * (s + w)
                # Seen from inside, the viewer looks along -inward; their right is (v_y, -v_x), v = -inward.
                right_dir = np.array([-inward[1], inward[0]])
                left, right = (a, b) if a @ right_dir < b @ right_dir else (b, a)
                corners = np.array([[*left, h], [*right, h], [*right, 0.0], [*left, 0.0]])
                tex = (
                    facade_texture(rng, w, h)
                    if self.facade_style is None
                    else styled_facade_texture(rng, w, h, self.facade_style)
                )
                facades.append(Facade(corners, tex))
                back = np.array([a, b, a - inward * 10.0, b - inward * 10.0])
                boxes.append(((back[:, 0].min(), back[:, 1].min(), back[:, 0].max(), back[:, 1].max()), h))
                s += w
        return facades, boxes

    def ground_level_for(self, camera) -> tuple:
        """(texture, tex_H_ground) of the pyramid level whose texel best matches the footprint of one pixel
        at the scene centre (avoids aliasing in low-resolution renders)."""
        dist = np.linalg.norm(camera.center - np.array([*self.config.center, 0.0]))
        footprint = dist / camera.K[0, 0]
        level = int(np.floor(np.log2(max(footprint / self.m_per_px, 1.0))))
        level = min(level, len(self.ground_levels) - 1)
        return self.ground_levels[level]

    @property
    def occluders(self) -> list:
        """Every occluding box as ((x0, y0, x1, y1), height): obstacles, distractors (vertical ones by their
        bounding square) and buildings."""
        return [(b, h) for b, h, _ in self.boxes] + self.distractors.round_boxes() + list(self.building_boxes)

    def crowd_config(self):
        """The scene config the crowd walks in: the distractors inside the area added as obstacles."""
        extra = self.distractors.crowd_obstacles()
        if not extra:
            return self.config
        return dataclasses.replace(self.config, pillars=list(self.config.pillars) + extra)
