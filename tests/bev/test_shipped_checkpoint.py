"""The shipped default detector (trained on simulated scenes only) on the REAL MATRIX sample: a
CI regression check (MODA >= 90 % on frames 0-4) and the end-to-end check that geometry, lifting and
decoding agree between simulation and reality. Frames 0-4 are the validation set the default was selected
on (docs/detector.md): this guards against regressions, it is no test accuracy."""

import pytest
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.data import BevFrames
from matrix_core.bev.evaluation import evaluate
from matrix_core.fusion.settings import shipped_checkpoint


@pytest.mark.slow
def test_shipped_checkpoint_on_real_sample(matrix_sample):
    torch.set_num_threads(1)
    model, settings = load_model(shipped_checkpoint())
    data = BevFrames(matrix_sample, settings)
    result = evaluate(model, data, progress=False)
    # measured when shipped: MODA 0.990, precision 1.000, recall 0.990 (scripts/detector_report.py)
    assert result.detection.moda >= 0.90, result.detection
    assert result.detection.precision >= 0.95, result.detection
    # the same model with two cameras removed still finds most people
    fewer = BevFrames(matrix_sample, settings, views=['D1', 'D3', 'D4', 'D5', 'D7', 'D8'])
    assert evaluate(model, fewer, progress=False).detection.moda > 0.8


@pytest.mark.slow
def test_the_faster_detector_on_real_sample(matrix_sample):
    # bev_tiny, the detector for computers where fuse must run in a third of the time (docs/detector.md):
    # measured when shipped MODA 0.965, precision 1.000 (scripts/detector_report.py, frames 0-4 are
    # its validation frames too)
    torch.set_num_threads(1)
    model, settings = load_model(shipped_checkpoint('detector_tiny_seed1.pt'))
    assert settings.model == 'bev_tiny'
    result = evaluate(model, BevFrames(matrix_sample, settings), progress=False)
    assert result.detection.moda >= 0.90, result.detection
    assert result.detection.precision >= 0.95, result.detection
