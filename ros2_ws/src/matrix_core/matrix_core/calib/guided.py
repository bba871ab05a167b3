"""Calibration guided by the drone's registration: the camera a registration's ground homography implies.

A registration maps this image to the drone's reference image, hence to the ground; with the scene's
intrinsics its ground homography implies a rigid camera, a prior independent of earlier frames (no drift:
every registration is to the same reference). That camera predicts the boards; the calibrator tracks their
corners (:mod:`matrix_core.calib.corner_tracking`) or searches near them, and rejects a pose that disagrees
with it (:func:`registration_disagreement`).
"""

import numpy as np

from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.homography import implied_camera

REGISTRATION_SHAPE_ERROR = 0.05  # a registration homography further from a rigid camera is not used


def registered_camera(scene: CalibScene, img_H_ground) -> tuple:
    """(Camera or None, how): the rigid camera a registration's ground homography implies.

    ``img_H_ground`` (3, 3) maps the ground (z = 0, world metres) to this image's pixels, or None (no
    registration: how is ''). When it is unusable or not a rigid camera with the scene's intrinsics, the
    camera is None and ``how`` says why (ending in '; ', it prefixes the note of the fallback)."""
    if img_H_ground is None:
        return None, ''
    H = np.asarray(img_H_ground, dtype=np.float64)
    if H.shape != (3, 3) or not np.all(np.isfinite(H)) or abs(np.linalg.det(H)) < 1e-12:
        return None, 'registration homography unusable; '
    implied = implied_camera(scene.K, H)
    if implied.shape_error > REGISTRATION_SHAPE_ERROR:
        return None, f'registration not a rigid camera (shape error {implied.shape_error:.3f}); '
    return scene.camera(pose_matrix(implied.R, implied.t)), 'registration'


def registration_disagreement(camera: Camera, guide: Camera, settings: CalibSettings) -> str:
    """Why ``camera`` (a solved pose) contradicts ``guide`` (the camera the registration implies), or ''."""
    apart_m = float(np.linalg.norm(camera.center - guide.center))
    if apart_m > settings.registration_agreement_m:
        return f'{apart_m:.2f} m from the camera the registration implies (> {settings.registration_agreement_m})'
    return ''
