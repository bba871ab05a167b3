"""Small rasterisation helpers: near-plane clipping, projection, OpenCV fixed-point polygons.

Convention: camera-frame points are OpenCV optical frame (z forward); pixels are the internal pixel-centre
convention, which is also OpenCV's drawing convention (integer coordinates are pixel centres), so a
polygon passed with :data:`SHIFT` fractional bits lands at its exact projected position.
"""

import numpy as np

SHIFT = 8  # fractional bits of polygon vertices given to OpenCV drawing functions
NEAR_M = 0.3  # near clipping plane, metres in front of the camera


def to_camera(camera, points_world) -> np.ndarray:
    """(..., 3) world points -> (..., 3) camera-frame points."""
    return points_world @ camera.R.T + camera.t


def project_camera_points(K, points_cam) -> np.ndarray:
    """(..., 3) camera-frame points with z > 0 -> (..., 2) pixels (ideal pinhole)."""
    uvw = points_cam @ K.T
    return uvw[..., :2] / uvw[..., 2:3]


def clip_near(poly_cam: np.ndarray, near: float = NEAR_M) -> np.ndarray:
    """Clip a convex (N, 3) camera-frame polygon to z >= ``near`` (Sutherland-Hodgman); may return (0, 3)."""
    inside = poly_cam[:, 2] >= near
    if inside.all():
        return poly_cam
    if not inside.any():
        return poly_cam[:0]
    out = []
    n = len(poly_cam)
    for k in range(n):
        a, b = poly_cam[k], poly_cam[(k + 1) % n]
        a_in, b_in = a[2] >= near, b[2] >= near
        if a_in:
            out.append(a)
        if a_in != b_in:
            s = (near - a[2]) / (b[2] - a[2])
            out.append(a + s * (b - a))
    return np.array(out)


def fixed(uv: np.ndarray) -> np.ndarray:
    """(N, 2) float pixels -> (N, 1, 2) int32 fixed-point vertices for ``shift=SHIFT`` drawing calls."""
    return np.round(np.clip(uv, -1e5, 1e5) * (1 << SHIFT)).astype(np.int32).reshape(-1, 1, 2)


def clip_half_plane_2d(poly: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Keep the part of a convex (N, 2) polygon where ``line @ (u, v, 1) >= 0``."""
    vals = poly @ line[:2] + line[2]
    out = []
    n = len(poly)
    for k in range(n):
        a, b, va, vb = poly[k], poly[(k + 1) % n], vals[k], vals[(k + 1) % n]
        if va >= 0:
            out.append(a)
        if (va >= 0) != (vb >= 0):
            out.append(a + va / (va - vb) * (b - a))
    return np.array(out).reshape(-1, 2)
