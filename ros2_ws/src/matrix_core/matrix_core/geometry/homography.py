"""Plane homographies.

Naming: ``a_H_b`` maps homogeneous points expressed in ``b`` to ``a`` (``p_a ~ a_H_b @ p_b``), exactly
like the transforms ``a_T_b``. Frames used in this project:

- ``img``: image pixels, OpenCV pixel-centre convention, unmirrored (see ``camera.py``);
- ``ground``: metres on a horizontal world plane (usually z = 0), coordinates (x, y);
- ``grid``: BEV cell indices (column, row) of a :class:`~matrix_core.geometry.grid.BevGrid`.
"""

from dataclasses import dataclass

import numpy as np

from matrix_core.geometry.checks import as_matrix, as_points


def pixel_scale_homography(sx: float, sy: float) -> np.ndarray:
    """``big_H_small`` for pixel-centre coordinates when 1 small pixel = (sx, sy) big pixels:
    u_big = (u_small + 0.5) * sx - 0.5 (``sx`` < 1 maps big pixels to small ones)."""
    return np.array([[sx, 0.0, 0.5 * sx - 0.5], [0.0, sy, 0.5 * sy - 0.5], [0.0, 0.0, 1.0]])


def apply_homography(a_H_b: np.ndarray, points_b) -> np.ndarray:
    """Map points through a homography.

    Args:
        a_H_b: (3, 3) homography from frame ``b`` to frame ``a``.
        points_b: (N, 2) points in ``b`` (a single (2,) point is accepted).

    Returns:
        (N, 2) points in ``a``. Points mapped to infinity (w == 0) come back as NaN rather than raising.
    """
    a_H_b = as_matrix(a_H_b, (3, 3), 'a_H_b')
    pts = as_points(points_b, 2, 'points_b')
    hom = np.concatenate([pts, np.ones((len(pts), 1))], axis=1) @ a_H_b.T
    with np.errstate(divide='ignore', invalid='ignore'):
        out = hom[:, :2] / hom[:, 2:3]
    out[~np.isfinite(out).all(axis=1)] = np.nan
    return out


def ground_homography(K: np.ndarray, cam_T_world: np.ndarray, plane_z: float = 0.0) -> np.ndarray:
    """Homography ``img_H_ground`` from the horizontal world plane z = ``plane_z`` to image pixels.

    Args:
        K: (3, 3) intrinsics (pixel-centre convention).
        cam_T_world: (4, 4) world-to-camera transform.
        plane_z: height of the plane in metres (0 for the ground, 0.1 for the MATRIX boards).

    Returns:
        (3, 3) ``img_H_ground``: maps (x, y, 1) in world metres on the plane to pixels. Lens distortion
        is ignored (a plane homography cannot express it).
    """
    K = as_matrix(K, (3, 3), 'K')
    cam_T_world = as_matrix(cam_T_world, (4, 4), 'cam_T_world')
    R, t = cam_T_world[:3, :3], cam_T_world[:3, 3]
    # A point (x, y, z0) maps to R[:, 0] x + R[:, 1] y + (R[:, 2] z0 + t).
    return K @ np.column_stack([R[:, 0], R[:, 1], R[:, 2] * plane_z + t])


@dataclass(frozen=True)
class ImpliedCamera:
    """Rigid camera recovered from a ground homography with known K.

    Attributes:
        R: (3, 3) world -> camera rotation (re-orthonormalised); t: (3,) translation.
        center: (3,) camera centre in world metres.
        shape_error: deviation of ``K^-1 H`` from two orthonormal columns (0 for an exact camera).
        K: (3, 3) the intrinsics it was recovered with.
    """

    R: np.ndarray
    t: np.ndarray
    center: np.ndarray
    shape_error: float
    K: np.ndarray = None


def implied_camera(K: np.ndarray, img_H_ground: np.ndarray) -> ImpliedCamera:
    """Decompose a (3, 3) ground -> pixel homography into the rigid camera it implies (intrinsics ``K``)."""
    M = np.linalg.solve(K, img_H_ground)
    n1, n2 = np.linalg.norm(M[:, 0]), np.linalg.norm(M[:, 1])
    shape_error = max(abs(1.0 - n1 / n2), abs(M[:, 0] @ M[:, 1]) / (n1 * n2))
    M = M / np.sqrt(n1 * n2)
    if M[2, 2] < 0:  # the ground must be in front of the camera: its origin-ray depth t_z > 0 ...
        M = -M
    r1, r2 = M[:, 0], M[:, 1]
    R = np.column_stack([r1, r2, np.cross(r1, r2)])
    U, _, Vt = np.linalg.svd(R)
    R = U @ Vt
    t = M[:, 2]
    return ImpliedCamera(R, t, -R.T @ t, float(shape_error), np.array(K, dtype=np.float64))


def normalized(H: np.ndarray) -> np.ndarray:
    """Scale a homography so that H[2, 2] == 1 (for comparisons and serialisation)."""
    H = as_matrix(H, (3, 3), 'H')
    if abs(H[2, 2]) < 1e-15:
        raise ValueError('homography has H[2, 2] == 0 and cannot be normalised')
    return H / H[2, 2]
