"""Where each board should appear in a new image, and a rectified view of it to search in.

The prior is the previous good pose (or the reference pose for the first frame), carried into the
current image by the ground homography of :mod:`matrix_core.calib.motion`. When that fails, a phase
correlation of two small grey images (about 1 ms at 1/8 scale) gives at least the global translation.
"""

import cv2
import numpy as np

from matrix_core.calib.board import Checkerboard
from matrix_core.geometry.camera import Camera


def translation(shift) -> np.ndarray:
    """(3, 3) homography moving pixels by ``shift`` (2,)."""
    return np.array([[1.0, 0.0, shift[0]], [0.0, 1.0, shift[1]], [0.0, 0.0, 1.0]])


def small_gray(gray: np.ndarray, scale: float) -> np.ndarray:
    """(H, W) uint8 -> (h, w) float32 image at ``scale`` for :func:`image_shift`."""
    return cv2.resize(gray, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA).astype(np.float32)


def image_shift(previous_small: np.ndarray, current_small: np.ndarray, scale: float) -> np.ndarray:
    """(2,) full-resolution pixels (du, dv) that content moved from the previous to the current image.

    Both inputs come from :func:`small_gray` with the same ``scale``. Returns zeros when the sizes differ.
    """
    if previous_small is None or previous_small.shape != current_small.shape:
        return np.zeros(2)
    window = cv2.createHanningWindow(current_small.shape[::-1], cv2.CV_32F)
    (du, dv), _response = cv2.phaseCorrelate(previous_small, current_small, window)
    return np.array([du, dv]) / scale


def image_H_board(camera: Camera, board: Checkerboard, cur_H_prev=None) -> np.ndarray:
    """(3, 3) homography: board corner coordinates (i, j) (fractional allowed) -> image pixels.

    ``camera`` is the prior (previous) pose; ``cur_H_prev`` (3, 3), when given, carries its image into
    the current one (see :mod:`matrix_core.calib.motion`). Assumes ``axis_i``/``axis_j`` are horizontal.
    """
    o = np.asarray(board.origin, dtype=np.float64)
    world_H_ij = np.array(
        [
            [board.axis_i[0] * board.square, board.axis_j[0] * board.square, o[0]],
            [board.axis_i[1] * board.square, board.axis_j[1] * board.square, o[1]],
            [0.0, 0.0, 1.0],
        ]
    )
    H = camera.img_H_ground(float(o[2])) @ world_H_ij
    return H if cur_H_prev is None else np.asarray(cur_H_prev, dtype=np.float64) @ H


def predict_boards(boards: list, camera: Camera, cur_H_prev=None) -> dict:
    """Board name -> (3, 3) current image pixels <- corner indices, for every board (see :func:`image_H_board`)."""
    return {board.name: image_H_board(camera, board, cur_H_prev) for board in boards}


def board_rectification(
    img_H_ij: np.ndarray, board: Checkerboard, camera: Camera, px_per_square: float = 10.0, margin_cells: float = 3.0
):
    """Homography and size of a fronto-parallel view of ``board`` predicted by ``img_H_ij``.

    In MATRIX images the boards are seen at a grazing angle (rows 3-6 px apart): a rectified view, where
    squares are about ``px_per_square`` pixels wide in both directions, is found far more reliably and
    faster by ``findChessboardCornersSB`` than the raw image region.

    Returns:
        (img_H_rect (3, 3): rectified pixels -> image pixels, (width, height)), or None when the predicted
        board (plus margin) crosses the horizon or misses the image (``camera`` gives the image size).
    """
    lo_i, lo_j = -1.0 - margin_cells, -1.0 - margin_cells
    hi_i, hi_j = board.nx + margin_cells, board.ny + margin_cells
    corners = np.array([[lo_i, lo_j, 1], [hi_i, lo_j, 1], [hi_i, hi_j, 1], [lo_i, hi_j, 1]]) @ img_H_ij.T
    if np.any(corners[:, 2] <= 1e-9):
        return None
    uv = corners[:, :2] / corners[:, 2:]
    if (
        uv[:, 0].max() < 0
        or uv[:, 1].max() < 0
        or uv[:, 0].min() > camera.width - 1
        or uv[:, 1].min() > camera.height - 1
    ):
        return None
    width = int(round((hi_i - lo_i) * px_per_square))
    height = int(round((hi_j - lo_j) * px_per_square))
    ij_H_rect = np.array([[1.0 / px_per_square, 0.0, lo_i], [0.0, 1.0 / px_per_square, lo_j], [0.0, 0.0, 1.0]])
    return img_H_ij @ ij_H_rect, (width, height)
