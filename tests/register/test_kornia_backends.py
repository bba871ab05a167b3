"""kornia GFTT-AffNet backends with offline weights: the missing-HardNet message, and the substitutes
registering one real pair at 480x270 (kornia is slow on a CPU)."""

import os

import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register.backends import BACKENDS, make_backend
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import RegisterSettings
from matrix_core.register.weights import HARDNET_FILE, MissingWeightsError


@pytest.fixture
def offline_torch_home(tmp_path, shared_dir, monkeypatch):
    """A torch hub cache holding exactly what `make setup` installs: links to shared/weights."""
    checkpoints = tmp_path / 'hub' / 'checkpoints'
    checkpoints.mkdir(parents=True)
    weights = shared_dir / 'weights'
    for name in ('AffNet.pth', 'OriNet.pth', 'keynet_pytorch.pth', 'tfeat-liberty.params'):
        os.symlink(weights / name, checkpoints / name)
    os.symlink(weights / 'extra' / 'HardTFeat.pth', checkpoints / 'HardTFeat.pth')
    monkeypatch.setenv('TORCH_HOME', str(tmp_path))
    return checkpoints


def test_missing_hardnet_weights_are_named_with_their_place(offline_torch_home):
    with pytest.raises(MissingWeightsError) as info:
        make_backend(RegisterSettings(backend='gftt_affnet_hardnet'))
    text = str(info.value)
    assert HARDNET_FILE in text
    assert str(offline_torch_home / HARDNET_FILE) in text
    assert 'not HardNet' in text  # the substitutes are named as substitutes


def test_missing_affnet_is_reported_too(offline_torch_home):
    (offline_torch_home / 'AffNet.pth').unlink()
    with pytest.raises(MissingWeightsError, match='AffNet.pth'):
        make_backend(RegisterSettings(backend='gftt_affnet_sift'))


def test_backends_come_from_the_registry():
    assert set(BACKENDS) == {'sift', 'gftt_affnet_hardnet', 'gftt_affnet_hardtfeat', 'gftt_affnet_sift'}
    with pytest.raises(ValueError, match='gftt_affnet_hardtfeat'):
        RegisterSettings(backend='akaze')


@pytest.mark.slow
@pytest.mark.parametrize('backend', ['gftt_affnet_hardtfeat', 'gftt_affnet_sift'])
def test_kornia_substitute_registers_a_real_pair_at_480x270(backend, offline_torch_home, matrix_sample):
    import torch

    torch.set_num_threads(1)
    dataset = MatrixDataset(matrix_sample)
    settings = RegisterSettings(backend=backend, scale=0.25, max_features=4000, reference_max_features=4000)
    ref = dataset.reference_camera('D3')
    registrar = Registrar(settings, dataset.reference_image('D3'), ref, dataset.area)
    assert registrar.backend.name == backend
    r = registrar.register(dataset.load_image('D3', 0), 0)
    assert r.ok, r.message
    assert r.backend == backend
    error = homography_error_px(r.ref_H_img, dataset.camera('D3', 0), ref, dataset.area, settings.exclude_boxes)
    assert error < 1.5, f'{backend}: {error:.2f} px'


@pytest.mark.slow
def test_kornia_mask_keeps_the_features_inside_it(offline_torch_home, matrix_sample):
    import numpy as np
    import torch

    torch.set_num_threads(1)
    image = MatrixDataset(matrix_sample).load_image('D3', 0)
    backend = make_backend(RegisterSettings(backend='gftt_affnet_sift', scale=0.25))
    everywhere = backend.extract(image, 2000)
    mask = np.zeros((270, 480), bool)
    mask[135:] = True  # the lower half of the 480x270 working image
    inside = backend.extract(image, 2000, mask)
    assert 0 < len(inside) < len(everywhere)
    assert np.all(inside.xy[:, 1] >= (135 - 0.5) / 0.25 - 0.5 - 2)
    assert len(inside) == int(np.sum(np.round((everywhere.xy[:, 1] + 0.5) * 0.25 - 0.5) >= 135))
