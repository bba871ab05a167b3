"""BevFrames on the real sample: calibration sources, view subsets, targets per frame."""

import numpy as np
import pytest

from matrix_core.bev.data import BevFrames
from matrix_core.bev.settings import BevSettings

SETTINGS = BevSettings(image_width=160, image_height=96, cell_m=0.5)


def test_calibration_sources(matrix_sample):
    gt = BevFrames(matrix_sample, SETTINGS, frames=[1, 3], cache_images=False)
    frozen = BevFrames(matrix_sample, SETTINGS, frames=[1, 3], calibration='frozen_first', cache_images=False)
    ref = BevFrames(matrix_sample, SETTINGS, frames=[1, 3], calibration='reference', cache_images=False)
    np.testing.assert_allclose(gt.homographies(1), frozen.homographies(1))  # same at the first frame
    # drones move: by frame 3 the frozen homography maps the grid elsewhere (many feature pixels)
    assert np.abs(gt.homographies(3) - frozen.homographies(3)).max() > 1e-3
    centre = np.array([gt.grid.nx / 2, gt.grid.ny / 2, 1.0])
    uv = lambda H: (H @ centre)[:, :2] / (H @ centre)[:, 2:]
    assert np.linalg.norm(uv(gt.homographies(3)) - uv(frozen.homographies(3)), axis=1).max() > 2.0
    assert np.linalg.norm(uv(gt.homographies(1)) - uv(ref.homographies(1)), axis=1).max() > 5.0
    with pytest.raises(ValueError, match='known'):
        BevFrames(matrix_sample, SETTINGS, calibration='guess')


def test_view_subset_and_items(matrix_sample):
    data = BevFrames(matrix_sample, SETTINGS, frames=[0, 1, 2], views=['D1', 'D5'])
    item = data[1]
    assert item['view_mask'].tolist() == [True, False, False, False, True, False, False, False]
    assert float(item['images'][1].abs().sum()) == 0.0 and float(item['images'][0].abs().sum()) > 0
    assert item['frame'] == 1 and item['prev_frame'] == 0 and data[0]['prev_frame'] == -1
    assert int(item['center_mask'].sum()) == 40 and int(item['tracking_mask'].sum()) == 40
    assert int(data[0]['tracking_mask'].sum()) == 0
    with pytest.raises(ValueError, match='no images'):
        BevFrames(matrix_sample, SETTINGS, frames=[0, 77])
