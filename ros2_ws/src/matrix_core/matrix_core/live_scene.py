"""What the live view draws, as geometry (no messages, no viewer): the area's outline, the obstacles' boxes,
each camera's frustum in its optical frame, the tracks' colours and their short trails.

World metres, z up (``matrix_core.geometry.camera``); the optical frame: x right, y down, z forward.
"""

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.geometry.occlusion import as_boxes
from matrix_core.register.settings import MATRIX_BLOCK


@dataclass
class LiveSceneSettings:
    """The scene of the live view: the area, the obstacles, how far the frustums reach, how long the trails are."""

    area: list[float] = field(
        default_factory=lambda: list(MATRIX_AREA),
        metadata={'help': 'pedestrian area x_min y_min x_max y_max (internal world metres), drawn as its outline'},
    )
    obstacle_boxes: list[float] = field(
        default_factory=lambda: list(MATRIX_BLOCK),
        metadata={
            'help': 'obstacles drawn as boxes, groups of 5 numbers x0 y0 x1 y1 height (metres); default: the '
            "MATRIX central block (a simulated folder's own come from its meta, scene_dataset)"
        },
    )
    frustum_depth_m: float = field(
        default=3.0, metadata={'help': "how far along its optical axis each camera's frustum is drawn (m)"}
    )
    trail_frames: int = field(
        default=10, metadata={'help': "frames of each track's trail (its last positions), 0 = no trails"}
    )

    def __post_init__(self):
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')
        as_boxes(self.obstacle_boxes)
        if not self.frustum_depth_m > 0 or self.trail_frames < 0:
            raise ValueError('frustum_depth_m must be positive and trail_frames >= 0')
        if hasattr(super(), '__post_init__'):  # composed with the node's settings
            super().__post_init__()


def area_outline(area) -> np.ndarray:
    """(5, 3) closed outline of ``area`` (x_min, y_min, x_max, y_max) on the ground."""
    x0, y0, x1, y1 = (float(v) for v in area)
    return np.array([[x0, y0, 0.0], [x1, y0, 0.0], [x1, y1, 0.0], [x0, y1, 0.0], [x0, y0, 0.0]])


def frustum_corners(K, width: int, height: int, depth_m: float) -> np.ndarray:
    """(4, 3) the image corners' rays at ``depth_m`` along the optical axis, in the camera's optical frame
    (top-left, top-right, bottom-right, bottom-left; pixel-centre convention: the image spans -0.5 .. W - 0.5)."""
    uv = np.array([[-0.5, -0.5], [width - 0.5, -0.5], [width - 0.5, height - 0.5], [-0.5, height - 0.5]])
    rays = np.column_stack([uv, np.ones(4)]) @ np.linalg.inv(np.asarray(K, dtype=np.float64).reshape(3, 3)).T
    return rays / rays[:, 2:3] * depth_m


def frustum_segments(K, width: int, height: int, depth_m: float) -> np.ndarray:
    """(16, 3) point pairs of the frustum's 8 edges (apex to each corner, and the far rectangle), optical frame."""
    c = frustum_corners(K, width, height, depth_m)
    apex = np.zeros(3)
    pairs = [(apex, c[i]) for i in range(4)] + [(c[i], c[(i + 1) % 4]) for i in range(4)]
    return np.array([p for pair in pairs for p in pair])


def track_rgb(track_id: int) -> tuple:
    """A distinct, stable colour per track id (golden-ratio hues): (r, g, b) in [0, 1]."""
    hue = (int(track_id) * 0.618034) % 1.0
    return (hue, 1.0 - hue, 0.5)


class Trails:
    """The last ``frames`` positions of each track; a track absent from a frame loses its trail."""

    def __init__(self, frames: int):
        self.frames, self.points = frames, {}

    def update(self, tracks) -> dict:
        """``tracks``: (id, (2,) xy) pairs of one frame -> {id: (M, 2) positions, oldest first, M <= frames}."""
        seen = {}
        for track_id, xy in tracks:
            trail = self.points.get(track_id) or deque(maxlen=max(1, self.frames))
            trail.append((float(xy[0]), float(xy[1])))
            seen[track_id] = trail
        self.points = seen
        return {k: np.array(v) for k, v in seen.items()} if self.frames else {}

    def reset(self) -> None:
        self.points = {}
