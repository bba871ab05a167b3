"""FrameNetwork (the inference form of the BEV network) gives what BevFusionNet.forward gives, on real frames of
the MATRIX sample with the shipped detectors (the default; bev_tiny's too in the first two tests): heatmaps, the
features carried to the next frame and the decoded detections, with and without a previous frame, with views
missing, and after a view's homography changed.

Tolerances: logits within 1e-3 (measured 3e-5: float32 rounding of the rearranged sums), carried features within
1e-4 (measured 7e-6), detections the same cells with positions and tracking offsets within 1e-5 m (measured 3e-7).
"""

import numpy as np
import pytest
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.data import BevFrames
from matrix_core.bev.decode import decode_detections
from matrix_core.bev.frame_network import FrameNetwork, fold_batch_norms
from matrix_core.bev.inference import SequenceRunner
from matrix_core.bev.registry import build_model
from matrix_core.fusion.settings import shipped_checkpoint

torch.set_num_threads(1)


@pytest.fixture(scope='module')
def shipped(matrix_sample):
    model, settings = load_model(shipped_checkpoint())
    data = BevFrames(matrix_sample, settings, frames=[0, 1, 2])
    return model, settings, data


def eager(model, x, mask, grid_shape, previous=None):
    with torch.no_grad():
        return model(x['images'][None], x['feat_H_grid'][None], mask[None], grid_shape, previous)


def assert_detections_equal(a, b):
    assert len(a.scores) == len(b.scores) > 0
    np.testing.assert_allclose(a.xy, b.xy, atol=1e-5)
    np.testing.assert_allclose(a.offsets, b.offsets, atol=1e-5)
    np.testing.assert_allclose(a.scores, b.scores, atol=1e-5)


@pytest.fixture(scope='module', params=['default', 'detector_tiny_seed1.pt'])
def each_shipped(request, shipped):
    """The default detector and the faster one (bev_tiny: other channel counts through the same rearrangement)."""
    if request.param == 'default':
        return shipped
    model, settings = load_model(shipped_checkpoint(request.param))
    return model, settings, shipped[2]


def test_outputs_equal_the_model_over_a_sequence(each_shipped):
    model, settings, data = each_shipped
    network = FrameNetwork(model, data.grid.shape)
    masks = [
        torch.ones(8, dtype=torch.bool),
        torch.tensor([1, 0, 1, 1, 0, 1, 1, 1], dtype=torch.bool),
        torch.ones(8, dtype=torch.bool),
    ]
    previous_eager = previous = None
    for frame, mask in zip(data.frames, masks):
        x = data.inputs(frame)
        ref = eager(model, x, mask, data.grid.shape, previous_eager)
        out = network(x['images'], x['feat_H_grid'], mask, previous)
        torch.testing.assert_close(out.heatmap, ref['heatmap'][0], atol=1e-3, rtol=0)
        torch.testing.assert_close(out.carry, ref['bev'], atol=1e-4, rtol=0)
        previous_eager, previous = ref['bev'], out.carry


def test_runner_detections_equal_decoding_the_model(each_shipped):
    model, settings, data = each_shipped
    runner = SequenceRunner(model, settings, data.grid)
    previous = None
    for frame in data.frames:
        x = data.inputs(frame)
        ref = eager(model, x, x['view_mask'], data.grid.shape, previous)
        expected = decode_detections(
            ref['heatmap'][0],
            ref['offset'][0],
            ref['tracking'][0],
            data.grid,
            settings.score_threshold,
            settings.nms_radius_m,
            settings.max_detections,
            settings.subcell,
        )
        got = runner.step(frame, x['images'], x['feat_H_grid'], x['view_mask'])
        assert_detections_equal(got.detections, expected)
        np.testing.assert_allclose(got.heatmap, torch.sigmoid(ref['heatmap'][0, 0]).numpy(), atol=1e-4)
        previous = ref['bev']


def test_a_changed_homography_is_not_served_from_the_cache(shipped):
    model, settings, data = shipped
    network = FrameNetwork(model, data.grid.shape)
    a, b = data.inputs(0), data.inputs(1)
    mask = torch.ones(8, dtype=torch.bool)
    network(a['images'], a['feat_H_grid'], mask)
    assert not torch.equal(a['feat_H_grid'], b['feat_H_grid'])  # the drones moved
    out = network(a['images'], b['feat_H_grid'], mask)
    ref = eager(model, {'images': a['images'], 'feat_H_grid': b['feat_H_grid']}, mask, data.grid.shape)
    torch.testing.assert_close(out.heatmap, ref['heatmap'][0], atol=1e-3, rtol=0)


def test_no_view_gives_the_model_output_of_no_view(shipped):
    model, settings, data = shipped
    x = data.inputs(0)
    none = torch.zeros(8, dtype=torch.bool)
    out = FrameNetwork(model, data.grid.shape)(x['images'], x['feat_H_grid'], none)
    torch.testing.assert_close(out.heatmap, eager(model, x, none, data.grid.shape)['heatmap'][0], atol=1e-4, rtol=0)


def test_offset_head_at_peaks_equals_the_full_map(shipped):
    model, settings, data = shipped
    x = data.inputs(2)
    network = FrameNetwork(model, data.grid.shape)
    out = network(x['images'], x['feat_H_grid'], x['view_mask'])
    rows, cols = torch.tensor([0, 5, 64, 127]), torch.tensor([0, 127, 64, 3])  # borders: zero padding
    tracking, offset = network.heads_at(out.fused, rows, cols, offset=True)
    with torch.no_grad():
        full = model.heads(out.fused.contiguous())
    torch.testing.assert_close(tracking, full['tracking'][0][:, rows, cols].T, atol=1e-5, rtol=0)
    torch.testing.assert_close(offset, full['offset'][0][:, rows, cols].T, atol=1e-5, rtol=0)


def test_fold_batch_norms_keeps_the_function():
    torch.manual_seed(0)
    model = build_model('bev_tiny').eval()
    for bn in [m for m in model.modules() if isinstance(m, torch.nn.BatchNorm2d)]:
        bn.running_mean.uniform_(-1, 1), bn.running_var.uniform_(0.5, 2), bn.weight.data.uniform_(0.5, 2)
    x = torch.randn(2, 3, 32, 48)
    folded = fold_batch_norms(model.encoder)
    assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in folded.modules())
    assert any(isinstance(m, torch.nn.BatchNorm2d) for m in model.encoder.modules())  # a copy: model intact
    with torch.no_grad():
        torch.testing.assert_close(folded(x), model.encoder(x), atol=1e-5, rtol=1e-5)


def test_an_encoder_with_signed_features_is_refused():
    model = build_model('bev_tiny').eval()
    model.encoder.fuse = model.encoder.fuse[:1]  # no final ReLU: the pooling's shortcut would be wrong
    with pytest.raises(ValueError, match='non-negative encoder features'):
        FrameNetwork(model, (8, 8))


def test_heads_at_no_peak(shipped):
    model, settings, data = shipped
    network = FrameNetwork(model, data.grid.shape)
    x = data.inputs(0)
    out = network(x['images'], x['feat_H_grid'], x['view_mask'])
    none = torch.zeros(0, dtype=torch.long)
    tracking, offset = network.heads_at(out.fused, none, none, offset=True)
    assert tracking.shape == offset.shape == (0, 2)


def test_a_warmed_up_network_gives_the_same_outputs_and_keeps_nothing(shipped):
    # the fuse node warms the network up before its first frame: zeros through both temporal passes
    model, settings, data = shipped
    cold, warm = FrameNetwork(model, data.grid.shape), FrameNetwork(model, data.grid.shape)
    x = data.inputs(data.frames[0])
    warm.warm_up(len(x['images']), (x['images'].shape[-1], x['images'].shape[-2]))
    assert not warm._taps  # no lifting taps of the zeros' identity warp is served to a real frame
    mask, previous = torch.ones(len(x['images']), dtype=torch.bool), {}
    for network in (cold, warm):
        first = network(x['images'], x['feat_H_grid'], mask)
        out = network(x['images'], x['feat_H_grid'], mask, first.carry)
        previous[id(network)] = (first.heatmap, out.heatmap, out.carry)
    for a, b in zip(previous[id(cold)], previous[id(warm)]):
        torch.testing.assert_close(a, b, atol=0, rtol=0)


def test_the_carry_computed_on_demand_or_ahead_gives_the_same_next_frame(shipped):
    # a frame's carry waits until the next frame reads it, or until prepare_next (the fuse node calls it once
    # the frame is published): the next frame's outputs are bit for bit those from the carry tensor
    model, settings, data = shipped
    network = FrameNetwork(model, data.grid.shape)
    x0, x1 = data.inputs(data.frames[0]), data.inputs(data.frames[1])
    mask = torch.ones(len(x0['images']), dtype=torch.bool)
    first = network(x0['images'], x0['feat_H_grid'], mask)
    with_previous = network(x1['images'], x1['feat_H_grid'], mask, first.carry)
    assert callable(with_previous._carry)  # not computed: nobody read it yet
    reference = network(x0['images'], x1['feat_H_grid'], mask, with_previous.carry)
    for prepare in (False, True):
        second = network(x1['images'], x1['feat_H_grid'], mask, first)
        if prepare:
            network.prepare_next(second)
            assert not callable(second._carry) and second.previous_term is not None
        third = network(x0['images'], x1['feat_H_grid'], mask, second)
        torch.testing.assert_close(second.heatmap, with_previous.heatmap, atol=0, rtol=0)
        torch.testing.assert_close(third.heatmap, reference.heatmap, atol=0, rtol=0)
        torch.testing.assert_close(third.carry, reference.carry, atol=0, rtol=0)
