"""Homographies in a MATRIX folder's own file frame (raw image pixels, the calibration files' world).

The conversions themselves live in :mod:`matrix_core.datasets.matrix_conventions`; here they are only
turned into the affine matrices that re-express a homography.
"""

import numpy as np

from matrix_core.datasets import matrix_conventions as conv


def _affine_of(fn) -> np.ndarray:
    """(3, 3) matrix of an affine map of the plane, measured by applying ``fn`` ((N, 2) -> (N, 2))."""
    basis = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    out = np.asarray(fn(basis), dtype=np.float64)[:, :2]
    A = np.eye(3)
    A[:2, 2] = out[0]
    A[:2, 0] = out[1] - out[0]
    A[:2, 1] = out[2] - out[0]
    return A


def to_matrix_file_frame(H_cur_to_ref: np.ndarray, H_img_to_ground: np.ndarray):
    """Internal homographies -> (H_cur_to_ref, H_img_to_ground) of the MATRIX files.

    Returns:
        ``H_cur_to_ref`` (3, 3): raw file pixels of the current image -> raw file pixels of the reference;
        ``H_img_to_ground`` (3, 3): raw file pixels -> the calibration files' world (x, y) metres on z = 0.
        Both normalised to H[2, 2] = 1.
    """
    pix = _affine_of(conv.pixels_to_file)          # internal pixels -> file pixels
    world = _affine_of(conv.world_to_file)         # internal ground metres -> file ground metres
    H_pix = pix @ H_cur_to_ref @ np.linalg.inv(pix)
    H_ground = world @ H_img_to_ground @ np.linalg.inv(pix)
    return H_pix / H_pix[2, 2], H_ground / H_ground[2, 2]
