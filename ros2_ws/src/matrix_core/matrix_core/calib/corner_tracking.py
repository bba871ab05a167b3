"""Tracking without a checkerboard search: the board corners a prediction puts in the image give a pose,
which :func:`~matrix_core.calib.grow.grow_pose` refines and verifies over several rounds.

The prediction comes either from the camera a registration implies (``track_registered``, see
:mod:`matrix_core.calib.guided`) or from the previous good pose carried into this image by the ORB ground
homography (opt-in ``track_corners``). A tracked pose still has to pass the calibrator's plausibility checks;
when it does not, the frame is searched (:mod:`matrix_core.calib.board_search`).
"""

import numpy as np

from matrix_core.calib.grow import MAX_MOVE_SQUARES, TRACK_VERIFY_SHIFT, grow_pose
from matrix_core.calib.pnp import solve_pnp
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings

TRACK_ROUNDS = 5  # at most this many poses re-solved from the saddles they verify, from the predicted corners


def predicted_camera(scene: CalibScene, settings: CalibSettings, predicted: dict):
    """The pose that sees every board corner where ``predicted`` (board name -> (3, 3) current image
    pixels <- corner indices) puts it, or None when too few corners are in view."""
    world, uv = [], []
    for board in scene.boards:
        ij = board.corner_indices()
        p = np.c_[ij, np.ones(len(ij))] @ predicted[board.name].T
        front = p[:, 2] > 1e-9
        pix = p[front, :2] / p[front, 2:]
        inside = scene.camera(np.eye(4)).in_image(pix, margin=4.0)
        world.append(board.corners_world()[front][inside])
        uv.append(pix[inside])
    world, uv = np.concatenate(world), np.concatenate(uv)
    if len(world) < settings.min_corners:
        return None
    fit = solve_pnp(world, uv, scene.camera(np.eye(4)), settings.pnp_ransac_px)
    return None if fit is None else fit.camera


def track_corners(gray: np.ndarray, scene: CalibScene, settings: CalibSettings, predicted: dict) -> tuple:
    """(PnPResult or None, whole-square correction or None) of the (H, W) grey image from the board corners
    ``predicted`` (board name -> (3, 3) image pixels <- corner indices) puts in it (see ``grow_pose``)."""
    camera = predicted_camera(scene, settings, predicted)
    if camera is None:
        return None, None
    fit, correction = grow_pose(gray, camera, scene, settings, TRACK_ROUNDS, verify_shift=TRACK_VERIFY_SHIFT)
    if fit is None and settings.track_start_move > MAX_MOVE_SQUARES:
        # Only as a second try: from a prediction the strict first pass can verify, the looser one converged
        # to a worse pose (measured: real D2 frame 0, 0.12 instead of 0.06 deg from a guide 0.14 deg off).
        fit, correction = grow_pose(
            gray, camera, scene, settings, TRACK_ROUNDS, settings.track_start_move, TRACK_VERIFY_SHIFT
        )
    return fit, correction
