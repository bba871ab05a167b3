"""Sanity gate: physical checks of a registration that the confidence c = inliers / matches misses.

A homography fitted to the buildings (facades) instead of the ground can have many inliers and a normal
confidence, but the ground homography it implies is not that of a real camera. Checks, on the current
image's implied ``img_H_ground = inv(ref_H_img) @ ref_img_H_ground``:

1. shape: ``K^-1 img_H_ground ~ [r1 r2 t]`` must have two orthonormal columns (a rigid camera with the
   reference's intrinsics K); deviation = max(|1 - |m1|/|m2||, |cos(m1, m2)|);
2. the camera it implies must be above the ground and within ``max_height_change_m`` of the reference
   camera's height;
3. area: the reference's visible ground polygon warped into the current image must keep its orientation
   (no line at infinity through it) and change its area by at most ``max_area_ratio``;
4. agreement with the previous frame: the implied camera centre moves at most ``max_step_m`` per frame.
"""

import cv2
import numpy as np

from matrix_core.geometry.homography import apply_homography, implied_camera


def polygon_area(pts: np.ndarray) -> float:
    """Signed area of a (N, 2) polygon (shoelace)."""
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def ground_polygon(ref_img_H_ground: np.ndarray, ground_xy: np.ndarray) -> np.ndarray:
    """(P, 2) convex hull, in reference pixels, of the reference's visible ground points (N, 2) metres."""
    uv = apply_homography(ref_img_H_ground, ground_xy)
    return cv2.convexHull(uv.astype(np.float32)).reshape(-1, 2).astype(np.float64)


def shape_tolerance(max_shape_error: float, inliers, shape_inliers: int = 100) -> float:
    """Largest shape error accepted for a fit with ``inliers`` inliers (None: ``max_shape_error``)."""
    if inliers is None or inliers >= shape_inliers:
        return max_shape_error
    return max_shape_error * float(np.sqrt(shape_inliers / max(int(inliers), 1)))


def check_registration(
    ref_H_img: np.ndarray,
    K: np.ndarray,
    ref_img_H_ground: np.ndarray,
    ref_center: np.ndarray,
    ref_polygon: np.ndarray,
    previous_center=None,
    frames_since_previous: int = 1,
    max_shape_error: float = 0.08,
    max_area_ratio: float = 2.5,
    max_height_change_m: float = 4.0,
    max_step_m: float = 3.0,
    inliers: int = None,
    shape_inliers: int = 100,
):
    """Run the gate. Returns (reason, implied camera): reason is '' when every check passes.

    Args:
        ref_H_img: (3, 3) current-image pixels -> reference-image pixels.
        K: (3, 3) intrinsics of the current image (assumed equal to the reference's).
        ref_img_H_ground: (3, 3) ground metres -> reference pixels.
        ref_center: (3,) reference camera centre; ref_polygon: (P, 2) reference pixels (:func:`ground_polygon`).
        previous_center: (3,) implied centre of the previous registered frame, or None.
        inliers: inliers of the fit (None: the shape tolerance is ``max_shape_error``, see :func:`shape_tolerance`).
    """
    img_H_ground = np.linalg.solve(ref_H_img, ref_img_H_ground)
    cam = implied_camera(K, img_H_ground)
    tolerance = shape_tolerance(max_shape_error, inliers, shape_inliers)
    if cam.shape_error > tolerance:
        return (
            f'gate: implied ground homography is not a rigid camera (shape error {cam.shape_error:.3f} '
            f'> {tolerance:.3f} for {inliers} inliers)'
        ), cam
    if cam.center[2] <= 0 or abs(cam.center[2] - ref_center[2]) > max_height_change_m:
        return (
            f'gate: implied camera height {cam.center[2]:.2f} m vs reference {ref_center[2]:.2f} m '
            f'(max change {max_height_change_m} m)'
        ), cam
    hom = np.c_[ref_polygon, np.ones(len(ref_polygon))] @ np.linalg.inv(ref_H_img).T
    if not (np.all(hom[:, 2] > 0) or np.all(hom[:, 2] < 0)):
        return 'gate: the horizon of the warped ground polygon crosses it', cam
    ratio = polygon_area(hom[:, :2] / hom[:, 2:3]) / polygon_area(ref_polygon)
    if not (1.0 / max_area_ratio <= ratio <= max_area_ratio):
        return f'gate: warped ground polygon area ratio {ratio:.2f} outside [1/{max_area_ratio}, {max_area_ratio}]', cam
    if previous_center is not None:
        step = float(np.linalg.norm(cam.center - previous_center))
        if step > max_step_m * max(1, frames_since_previous):
            return (
                f'gate: implied camera moved {step:.2f} m since the previous registered frame '
                f'(max {max_step_m} m per frame)'
            ), cam
    return '', cam
