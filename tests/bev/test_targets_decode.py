"""Targets from the real sample's positions, decoded back to the same positions."""

import numpy as np
import torch

from matrix_core.bev.data import ground_truth_positions
from matrix_core.bev.decode import decode_detections
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.targets import bev_targets
from matrix_core.datasets import open_dataset
from matrix_core.metrics import BevPoints, detection_metrics


def test_targets_decode_to_ground_truth(matrix_sample):
    ds = open_dataset(matrix_sample)
    grid = BevSettings().grid(ds.area)
    pos, prev = ground_truth_positions(ds, 3), ground_truth_positions(ds, 2)
    assert len(pos) == 40
    t = bev_targets(grid, pos, prev, sigma_m=0.3)
    assert t['heatmap'].shape == (1,) + grid.shape and t['center_mask'].sum() == 40
    assert t['heatmap'].max() == 1.0 and (t['heatmap'] == 1).sum() == 40
    logits = torch.logit(torch.from_numpy(t['heatmap']).clamp(1e-4, 1 - 1e-4))
    dets = decode_detections(
        logits,
        torch.from_numpy(t['offset']),
        torch.from_numpy(t['tracking']),
        grid,
        score_threshold=0.5,
        nms_radius_m=0.5,
        subcell='offset',
    )
    assert len(dets) == 40
    gt_xy = np.array([pos[i] for i in sorted(pos)])
    d = np.linalg.norm(dets.xy[:, None] - gt_xy[None], axis=2)
    nearest = d.argmin(1)
    assert d.min(1).max() < 1e-5  # exact positions via the sub-cell offsets
    ids = sorted(pos)
    back = dets.xy + dets.offsets  # tracking offsets lead to the previous positions
    np.testing.assert_allclose(back, [prev[ids[k]] for k in nearest], atol=1e-5)
    m = detection_metrics(BevPoints(np.zeros(40), gt_xy), BevPoints(np.zeros(len(dets)), dets.xy))
    assert m.moda == 1.0
    # the 3x3 score centroid of the Gaussian targets alone recovers much of the sub-cell position
    error = {}
    for subcell in ('heatmap', 'none'):
        xy = decode_detections(
            logits, torch.zeros(2, *grid.shape), torch.zeros(2, *grid.shape), grid, 0.5, 0.5, subcell=subcell
        ).xy
        error[subcell] = np.linalg.norm(xy[:, None] - gt_xy[None], axis=2).min(1).mean()
    print(error)
    assert error['heatmap'] < 0.7 * error['none']  # 0.060 vs 0.101 m (the 3x3 window truncates)


def test_nms_keeps_one_peak_per_person():
    from matrix_core.geometry.grid import BevGrid

    grid = BevGrid(0, 0, 5, 5, 0.25)
    heat = torch.full((1, 20, 20), -10.0)
    heat[0, 10, 10] = 3.0
    heat[0, 10, 11] = 2.0  # shoulder of the same peak: suppressed
    heat[0, 2, 2] = 1.0  # another person
    zeros = torch.zeros(2, 20, 20)
    dets = decode_detections(heat, zeros, zeros, grid, score_threshold=0.5, nms_radius_m=0.5, subcell='none')
    assert len(dets) == 2 and dets.scores[0] > dets.scores[1]
    np.testing.assert_allclose(dets.xy[0], grid.cell_to_world(np.array([[10.0, 10.0]]))[0])
    # the heatmap centroid leans towards the shoulder (+x) by its share of the 3x3 scores
    lean = decode_detections(heat, zeros, zeros, grid, 0.5, 0.5, subcell='heatmap').xy[0]
    p, q = torch.sigmoid(torch.tensor(3.0)), torch.sigmoid(torch.tensor(2.0))
    w = float(q / (p + q + 7 * torch.sigmoid(torch.tensor(-10.0))))
    np.testing.assert_allclose(lean - dets.xy[0], [w * 0.25, 0.0], atol=1e-5)
    bad = heat.clone()
    bad[0, 0, 0] = float('nan')
    try:
        decode_detections(bad, zeros, zeros, grid)
    except ValueError as exc:
        assert 'NaN' in str(exc)
    else:
        raise AssertionError('NaN heatmap must raise')
