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
from matrix_core.register.registration import Registration, RegistrationError, RegistrationStatus

# Stricter than register's gate (which only rejects fits to the facades): a guide must predict the boards'
# corners within a few pixels, so a registration further from a rigid camera is not used to guide.
REGISTRATION_SHAPE_ERROR = 0.05


def registered_camera(scene: CalibScene, registration: Registration = None) -> tuple:
    """(Camera or None, how): the rigid camera a :class:`Registration` of this image implies.

    No registration, or one that register reported failed or bad input: (None, ''), the image motion guides
    silently (the node logs the failure). A registration that is unusable (bad data) or not a rigid camera with
    the scene's intrinsics: the camera is None and ``how`` says why (ending in '; ', it prefixes the note of the
    fallback)."""
    if registration is None or registration.status in (RegistrationStatus.FAILED, RegistrationStatus.BAD_INPUT):
        return None, ''
    try:
        implied = registration.implied_camera(scene.K)
    except RegistrationError:
        return None, 'registration homography unusable; '
    if implied.shape_error > REGISTRATION_SHAPE_ERROR:
        return None, f'registration not a rigid camera (shape error {implied.shape_error:.3f}); '
    return scene.camera(pose_matrix(implied.R, implied.t)), 'registration'


def registration_disagreement(camera: Camera, guide: Camera, settings: CalibSettings) -> str:
    """Why ``camera`` (a solved pose) contradicts ``guide`` (the camera the registration implies), or ''."""
    apart_m = float(np.linalg.norm(camera.center - guide.center))
    if apart_m > settings.registration_agreement_m:
        return f'{apart_m:.2f} m from the camera the registration implies (> {settings.registration_agreement_m})'
    return ''
