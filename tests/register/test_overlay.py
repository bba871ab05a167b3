"""Overlay pictures of a registration (current image warped onto the reference, checkerboard, ground grid)."""

import cv2
import numpy as np

from matrix_core.datasets import MatrixDataset
from matrix_core.register.evaluate import gt_cur_to_ref
from matrix_core.register.overlay import registration_overlay, write_registration_overlay


def test_overlay_warps_the_current_image_onto_the_reference(matrix_sample, tmp_path):
    dataset = MatrixDataset(matrix_sample)
    ref_cam, cur_cam = dataset.reference_camera('D4'), dataset.camera('D4', 1)
    reference = dataset.reference_image('D4')
    current = dataset.load_image('D4', 1)
    H = gt_cur_to_ref(cur_cam, ref_cam)
    small = cv2.resize(reference, (960, 540), interpolation=cv2.INTER_AREA).astype(float)
    rows, cols = np.indices((540, 960))
    warped_tiles = ((rows // 64 + cols // 64) % 2).astype(bool)
    S = np.diag([0.5, 0.5, 1.0])
    S[:2, 2] = -0.25  # full-resolution pixel centres -> half-resolution pixel centres
    covered = cv2.warpPerspective(np.ones((1080, 1920), np.uint8), S @ H, (960, 540), flags=cv2.INTER_NEAREST) > 0
    covered &= rows > 100  # the plaza, below the buildings

    def tile_difference(H_used):
        picture = registration_overlay(current, reference, H_used, ref_cam, dataset.area, grid_m=1000.0)
        assert picture.shape == (540, 960, 3) and picture.dtype == np.uint8
        sel = warped_tiles & covered
        return float(np.mean(np.abs(picture[sel].astype(float) - small[sel])))

    # The warped current tiles agree with the reference where the homography is right, not when it is off.
    shifted = np.array([[1, 0, 25.0], [0, 1, 15.0], [0, 0, 1]]) @ H
    assert tile_difference(H) < 0.7 * tile_difference(shifted)
    # The ground grid is drawn (green) and the file is written; a failed registration still gets a picture.
    path = write_registration_overlay(tmp_path / 'o' / 'x.png', current, reference, H, ref_cam, dataset.area, 'D4 1')
    picture = cv2.imread(str(path))
    green = (picture[..., 1] > 200) & (picture[..., 0] < 80) & (picture[..., 2] < 80)
    assert green.sum() > 2000
    failed = registration_overlay(current, reference, None, ref_cam, dataset.area, 'failed: no matches')
    assert failed.shape == (540, 960, 3)
