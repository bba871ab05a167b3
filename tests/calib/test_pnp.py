"""solve_pnp on correspondences that make OpenCV's SQPnP assert (found by the tracked calibration of a
simulated modified sequence: 678 board corners predicted by a poor ground homography)."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from matrix_core.calib.pnp import solve_pnp
from matrix_core.geometry.camera import Camera

DEGENERATE = Path(__file__).parent / 'fixtures' / 'sqpnp_degenerate.npz'


def test_an_assertion_of_sqpnp_gives_no_pose_instead_of_an_exception():
    d = np.load(DEGENERATE)
    cv2.setRNGSeed(0)
    with pytest.raises(cv2.error):  # the input really makes OpenCV assert
        cv2.solvePnPRansac(
            d['world'],
            d['img'],
            d['K'],
            d['dist'],
            reprojectionError=2.0,
            confidence=0.999,
            iterationsCount=200,
            flags=cv2.SOLVEPNP_SQPNP,
        )
    cv2.setRNGSeed(0)
    intrinsics = Camera(d['K'], np.eye(4), 1920, 1080, d['dist'])
    assert solve_pnp(d['world'].reshape(-1, 3), d['img'].reshape(-1, 2), intrinsics) is None
