"""Reference features are kept only where the reference camera sees the scene ground."""

import cv2
import numpy as np

from matrix_core.datasets import MatrixDataset
from matrix_core.register.backend_sift import SiftBackend
from matrix_core.register.ground_mask import ground_pixels
from matrix_core.register.reference import Reference
from matrix_core.register.settings import MATRIX_BLOCK


def test_reference_keeps_ground_features_only(matrix_sample):
    cv2.setNumThreads(1)
    dataset = MatrixDataset(matrix_sample)
    cam = dataset.reference_camera('D1')
    features = SiftBackend(0.25, 0.005).extract(dataset.reference_image('D1'), 16000)
    ref = Reference('D1/reference', cam, features, dataset.area, True, 0.0, MATRIX_BLOCK)
    assert 100 < len(ref.features) < len(features)
    ground = cam.backproject_to_ground(ref.features.xy)
    x0, y0, x1, y1 = dataset.area
    assert np.all((ground[:, 0] >= x0) & (ground[:, 0] <= x1) & (ground[:, 1] >= y0) & (ground[:, 1] <= y1))
    # None lies on the block's footprint (the block hides it).
    bx0, by0, bx1, by1, _ = MATRIX_BLOCK
    on_block = (ground[:, 0] > bx0) & (ground[:, 0] < bx1) & (ground[:, 1] > by0) & (ground[:, 1] < by1)
    assert not on_block.any()


def test_block_faces_sky_and_outside_are_not_ground(matrix_sample):
    dataset = MatrixDataset(matrix_sample)
    cam = dataset.reference_camera('D3')
    probes = np.array([[5.0, -5.0, 0.0],     # plaza ground
                       [15.0, -15.0, 8.0],   # the block's body, 8 m up (its ground ray lands behind it)
                       [15.0, -19.0, 0.0],   # ground right behind the block: hidden
                       [-8.0, -15.0, 0.0]])  # ground outside the area
    uv = cam.project(probes)
    assert np.all(cam.in_image(uv))
    keep = ground_pixels(cam, np.vstack([uv, [[960.0, 0.0]]]), dataset.area, 0.0, MATRIX_BLOCK)
    assert keep.tolist() == [True, False, False, False, False]  # last probe: top row of the image
