"""Which reference pixels see the scene ground (the only features that obey the ground homography).

Uses the reference calibration: a pixel is ground when its ray hits the plane z = 0 inside the scene
area (grown by a margin) and it is not covered by an obstacle box (the MATRIX central block), i.e. not
inside the image of the box's solid (which also hides the ground behind it). Buildings and sky back-project
outside the area or above the horizon and are dropped too.
"""

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera


def _box_corners(box) -> np.ndarray:
    """(8, 3) corners of an obstacle ``(x0, y0, x1, y1, height)`` standing on the ground."""
    x0, y0, x1, y1, h = box
    return np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (0.0, h)], dtype=np.float64)


def obstacle_mask(camera: Camera, boxes) -> np.ndarray:
    """(H, W) bool: pixels showing any of the ``boxes`` (flat list, groups of 5 numbers)."""
    mask = np.zeros((camera.height, camera.width), np.uint8)
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 5)
    for box in boxes:
        corners = _box_corners(box)
        depth = camera.depth(corners)
        # A box reaching behind the camera is approximated by its corners in front of it.
        corners = corners[depth > 0]
        if len(corners) < 3:
            continue
        uv = camera.project(corners)
        uv = uv[np.all(np.isfinite(uv), axis=1)]
        if len(uv) >= 3:
            hull = cv2.convexHull(np.round(uv).astype(np.int64).clip(-10 ** 6, 10 ** 6).astype(np.int32))
            cv2.fillConvexPoly(mask, hull, 1)
    return mask.astype(bool)


def ground_pixels(camera: Camera, xy: np.ndarray, area, margin_m: float = 0.0, boxes=(),
                  obstacles: np.ndarray = None) -> np.ndarray:
    """(N,) bool: which (N, 2) full-resolution pixels of ``camera`` see the ground inside ``area``.

    Args:
        camera: calibration of the image the pixels belong to.
        xy: (N, 2) pixel-centre coordinates.
        area: (x_min, y_min, x_max, y_max) internal world metres (the dataset's ``area``).
        margin_m: grow the area by this much on each side.
        boxes: obstacles, flat list of groups ``x0 y0 x1 y1 height`` (ignored if ``obstacles`` is given).
        obstacles: precomputed :func:`obstacle_mask` of ``camera``.
    """
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    ground = camera.backproject_to_ground(xy)
    x0, y0, x1, y1 = area
    with np.errstate(invalid='ignore'):
        keep = ((ground[:, 0] >= x0 - margin_m) & (ground[:, 0] <= x1 + margin_m)
                & (ground[:, 1] >= y0 - margin_m) & (ground[:, 1] <= y1 + margin_m))
    if obstacles is None:
        obstacles = obstacle_mask(camera, boxes)
    cols = np.clip(np.round(xy[:, 0]).astype(np.int64), 0, camera.width - 1)
    rows = np.clip(np.round(xy[:, 1]).astype(np.int64), 0, camera.height - 1)
    return keep & ~obstacles[rows, cols]


def visible_ground_grid(camera: Camera, area, step_m: float = 0.5, boxes=(), margin_px: float = 0.0) -> np.ndarray:
    """(N, 2) world metres of a ``step_m`` grid over ``area`` whose image in ``camera`` is visible ground.

    The evaluation grid of the acceptance metric and the polygon of the sanity gate.
    """
    x0, y0, x1, y1 = area
    gx, gy = np.meshgrid(np.arange(x0, x1 + 1e-9, step_m), np.arange(y0, y1 + 1e-9, step_m))
    world = np.stack([gx.ravel(), gy.ravel()], axis=1)
    uv = camera.ground_to_img(world)
    finite = np.all(np.isfinite(uv), axis=1) & (camera.depth(np.c_[world, np.zeros(len(world))]) > 0)
    vis = finite.copy()
    vis[finite] = camera.in_image(uv[finite], margin_px)
    if len(boxes) and vis.any():
        obstacles = obstacle_mask(camera, boxes)
        idx = np.flatnonzero(vis)
        cols = np.round(uv[idx, 0]).astype(np.int64).clip(0, camera.width - 1)
        rows = np.round(uv[idx, 1]).astype(np.int64).clip(0, camera.height - 1)
        vis[idx[obstacles[rows, cols]]] = False
    return world[vis]
