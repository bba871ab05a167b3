"""Robust perspective-n-point with known intrinsics: RANSAC, then Levenberg-Marquardt on the inliers."""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera


@dataclass
class PnPResult:
    """``camera`` (scene intrinsics, solved pose), ``inliers`` (N,) bool, RMS / max reprojection of inliers."""

    camera: Camera
    inliers: np.ndarray
    rms_px: float
    max_px: float


def reprojection_errors(camera: Camera, world: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(N,) pixel distances between (N, 2) ``uv`` and the projections of (N, 3) ``world``."""
    return np.linalg.norm(camera.project(world) - uv, axis=1)


def solve_pnp(world: np.ndarray, uv: np.ndarray, intrinsics: Camera, ransac_threshold_px: float = 2.0):
    """Pose of the camera seeing (N, 3) world points at (N, 2) pixels (N >= 6), or None.

    Args:
        intrinsics: camera whose K, dist and size are used (its pose is ignored).
    """
    world = np.ascontiguousarray(world, dtype=np.float64).reshape(-1, 1, 3)
    img = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 1, 2)
    if len(world) < 6:
        return None
    kwargs = dict(
        reprojectionError=ransac_threshold_px, confidence=0.999, iterationsCount=200, flags=cv2.SOLVEPNP_SQPNP
    )
    try:
        ok, rvec, tvec, inl = cv2.solvePnPRansac(world, img, intrinsics.K, intrinsics.dist, **kwargs)
    except cv2.error:  # SQPnP asserts on degenerate samples (measured: corners predicted by a bad homography)
        return None
    if not ok or inl is None or len(inl) < 6:
        return None
    inliers = np.zeros(len(world), dtype=bool)
    inliers[inl.ravel()] = True
    rvec, tvec = cv2.solvePnPRefineLM(world[inliers], img[inliers], intrinsics.K, intrinsics.dist, rvec, tvec)
    if not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):
        return None
    cam = Camera.from_rvec_tvec(intrinsics.K, rvec, tvec, intrinsics.width, intrinsics.height, intrinsics.dist)
    err = reprojection_errors(cam, world.reshape(-1, 3), img.reshape(-1, 2))
    # Re-derive inliers from the refined pose (RANSAC's set came from a minimal-sample pose).
    inliers = err <= ransac_threshold_px
    if inliers.sum() < 6:
        return None
    return PnPResult(cam, inliers, float(np.sqrt(np.mean(err[inliers] ** 2))), float(err[inliers].max()))
