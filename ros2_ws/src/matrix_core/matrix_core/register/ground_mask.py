"""Which reference pixels see the scene ground (the only features that obey the ground homography).

Uses the reference calibration: a pixel is ground when its ray hits the plane z = 0 inside the scene
area (grown by a margin) and the segment from the camera centre to that ground point does not pass through
an obstacle box (the MATRIX central block) first: pixels showing the box and the ground it hides are
dropped. The test is exact per ray (:func:`~matrix_core.geometry.occlusion.segments_blocked`), not a
polygon of the box's projected corners, which is meaningless for a box reaching behind the camera or
near its principal plane. Buildings and sky back-project outside the area or above the horizon and are
dropped too.
"""

import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.geometry.occlusion import segments_blocked
from matrix_core.register.features import to_full_resolution


def hidden_ground(camera: Camera, world_xy: np.ndarray, boxes) -> np.ndarray:
    """(N,) bool: which (N, 2) ground points (world metres, z = 0) a box hides from ``camera``'s centre.

    ``boxes``: flat list of groups ``x0 y0 x1 y1 height`` (or (K, 5)). NaN points are not hidden.
    """
    world_xy = np.asarray(world_xy, dtype=np.float64).reshape(-1, 2)
    if not len(world_xy) or not np.size(boxes):
        return np.zeros(len(world_xy), dtype=bool)
    return segments_blocked(camera.center, np.c_[world_xy, np.zeros(len(world_xy))], boxes)


def ground_pixels(camera: Camera, xy: np.ndarray, area, margin_m: float = 0.0, boxes=()) -> np.ndarray:
    """(N,) bool: which (N, 2) full-resolution pixels of ``camera`` see the ground inside ``area``.

    Args:
        camera: calibration of the image the pixels belong to.
        xy: (N, 2) pixel-centre coordinates.
        area: (x_min, y_min, x_max, y_max) internal world metres (the dataset's ``area``).
        margin_m: grow the area by this much on each side.
        boxes: obstacles, flat list of groups ``x0 y0 x1 y1 height``.
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    ground = camera.backproject_to_ground(xy)
    x0, y0, x1, y1 = area
    with np.errstate(invalid='ignore'):
        keep = (
            (ground[:, 0] >= x0 - margin_m)
            & (ground[:, 0] <= x1 + margin_m)
            & (ground[:, 1] >= y0 - margin_m)
            & (ground[:, 1] <= y1 + margin_m)
        )
    keep[keep] = ~hidden_ground(camera, ground[keep, :2], boxes)
    return keep


def ground_mask(camera: Camera, scale: float, area, margin_m: float = 0.0, boxes=()) -> np.ndarray:
    """(h, w) bool: :func:`ground_pixels` at the pixel centres of ``camera``'s image resized by ``scale``
    (the size :func:`~matrix_core.register.features.resize` gives)."""
    w, h = max(1, round(camera.width * scale)), max(1, round(camera.height * scale))
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    xy = to_full_resolution(np.column_stack([u.ravel(), v.ravel()]), scale)
    return ground_pixels(camera, xy, area, margin_m, boxes).reshape(h, w)


def visible_ground_grid(camera: Camera, area, step_m: float = 0.5, boxes=(), margin_px: float = 0.0) -> np.ndarray:
    """(N, 2) world metres of a ``step_m`` grid over ``area`` whose image in ``camera`` is visible ground:
    in front of the camera, inside the image (shrunk by ``margin_px``) and not hidden by ``boxes``.

    The evaluation grid of the acceptance metric and the polygon of the sanity gate.
    """
    x0, y0, x1, y1 = area
    gx, gy = np.meshgrid(np.arange(x0, x1 + 1e-9, step_m), np.arange(y0, y1 + 1e-9, step_m))
    world = np.stack([gx.ravel(), gy.ravel()], axis=1)
    uv = camera.ground_to_img(world)
    finite = np.all(np.isfinite(uv), axis=1) & (camera.depth(np.c_[world, np.zeros(len(world))]) > 0)
    vis = finite.copy()
    vis[finite] = camera.in_image(uv[finite], margin_px)
    vis[vis] = ~hidden_ground(camera, world[vis], boxes)
    return world[vis]
