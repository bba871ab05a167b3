"""The register node's start-up warm-up (``matrix_core.register.warm_up``): a throwaway registration of a real
drone's reference image to itself, by features and then by flow, once per process."""

import numpy as np

from matrix_core.datasets import MatrixDataset
from matrix_core.register import warm_up
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings


def test_warm_up_runs_the_feature_and_flow_paths_once(matrix_sample, monkeypatch):
    monkeypatch.setattr(warm_up, '_warmed', [])  # as in a new process
    dataset = MatrixDataset(matrix_sample)
    settings, _ = settings_for_dataset(RegisterSettings(), dataset)  # the live default (mode track)
    args = (settings, dataset.reference_image('D3'), dataset.reference_camera('D3'), dataset.area)
    anchor, tracked = warm_up.warm_up_once(*args)
    assert anchor.ok and anchor.message.startswith('anchor: no registered previous frame')  # SIFT, matched, fitted
    assert tracked.ok and tracked.message.startswith('tracked')  # optical flow
    for result in (anchor, tracked):  # the reference registered to itself
        assert result.inliers >= 40
        np.testing.assert_allclose(result.ref_H_img / result.ref_H_img[2, 2], np.eye(3), atol=2e-3)
    assert warm_up.warm_up_once(*args) == []  # once per process
