"""Shapes and masking behaviour of the BEV network (random weights, real sample geometry)."""

import numpy as np
import pytest
import torch

from matrix_core.bev.aggregation import masked_view_pool
from matrix_core.bev.data import BevFrames
from matrix_core.bev.registry import MODELS, build_model
from matrix_core.bev.settings import BevSettings

torch.set_num_threads(1)
SETTINGS = BevSettings(model='bev_tiny', image_width=160, image_height=96, cell_m=0.5)


@pytest.fixture(scope='module')
def frame_inputs(matrix_sample):
    data = BevFrames(matrix_sample, SETTINGS, frames=[1, 2])
    return data, data[1]


@pytest.fixture(scope='module')
def model():
    torch.manual_seed(0)
    return build_model('bev_tiny').eval()


def run(model, item, grid_shape, mask=None, images=None, previous=None):
    m = item['view_mask'] if mask is None else mask
    x = item['images'] if images is None else images
    with torch.no_grad():
        return model(x[None], item['feat_H_grid'][None], m[None], grid_shape, previous)


def test_output_shapes(model, frame_inputs):
    data, item = frame_inputs
    assert item['images'].shape == (8, 3, 96, 160) and item['feat_H_grid'].shape == (8, 3, 3)
    assert data.grid.shape == (64, 64)  # 30 m + 2 x 1 m margin at 0.5 m
    out = run(model, item, data.grid.shape)
    assert out['heatmap'].shape == (1, 1, 64, 64)
    assert out['offset'].shape == out['tracking'].shape == (1, 2, 64, 64)
    assert out['bev'].shape[-2:] == (64, 64)
    assert all(torch.isfinite(v).all() for v in out.values())


def test_missing_view_is_a_mask_bit_not_data(model, frame_inputs):
    data, item = frame_inputs
    mask = item['view_mask'].clone()
    mask[[1, 5]] = False
    noisy = item['images'].clone()
    noisy[[1, 5]] = torch.randn_like(noisy[[1, 5]]) * 5  # garbage in the masked views ...
    a = run(model, item, data.grid.shape, mask)
    b = run(model, item, data.grid.shape, mask, images=noisy)
    torch.testing.assert_close(a['heatmap'], b['heatmap'])  # ... changes nothing
    full = run(model, item, data.grid.shape)
    assert not torch.allclose(full['heatmap'], a['heatmap'])  # while the views do count when present


@pytest.mark.parametrize('views', [[0], [2, 3], [0, 1, 2, 3, 4, 5, 6, 7]])
def test_any_subset_of_views(model, frame_inputs, views):
    data, item = frame_inputs
    mask = torch.zeros(8, dtype=torch.bool)
    mask[views] = True
    out = run(model, item, data.grid.shape, mask)
    assert torch.isfinite(out['heatmap']).all()


def test_masked_pool_mean_and_count():
    bev = torch.tensor([1.0, 3.0, 100.0]).reshape(1, 3, 1, 1, 1)
    seen = torch.ones(1, 3, 1, 1, 1)
    pooled = masked_view_pool(bev, seen, torch.tensor([[True, True, False]]))
    np.testing.assert_allclose(pooled.flatten().numpy(), [2.0, 3.0, 2 / 3])
    nobody = masked_view_pool(bev, torch.zeros_like(seen), torch.tensor([[True, True, True]]))
    np.testing.assert_allclose(nobody.flatten().numpy(), [0.0, 0.0, 0.0])


def test_temporal_previous_changes_output_and_registry(model, frame_inputs):
    data, item = frame_inputs
    first = run(model, item, data.grid.shape)
    second = run(model, item, data.grid.shape, previous=first['bev'])
    assert not torch.allclose(first['heatmap'], second['heatmap'])
    # the features handed on are the one-step memory training feeds, not a chain over all past frames
    torch.testing.assert_close(second['bev'], first['bev'])
    assert {'bev_small', 'bev_tiny'} <= set(MODELS)
    with pytest.raises(ValueError, match='known'):
        build_model('resnet_from_a_string_if_elif')
