"""Training augmentation: the scale-and-crop keeps each annotated foot point on its BEV cell and on the same
image content; photometric changes keep the geometry; seeded runs repeat; disabled changes nothing."""

import numpy as np
import pytest
import torch

from matrix_core.bev.augment import AugmentConfig, photometric
from matrix_core.bev.config import SequenceSpec, TrainConfig, load_config
from matrix_core.bev.data import MEAN, PAD_RGB, STD, BevFrames, ground_truth_positions
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.training import augment_rng
from matrix_core.geometry.homography import apply_homography, pixel_scale_homography

SETTINGS = BevSettings(image_width=320, image_height=176, cell_m=0.25)
FRAME = 2
GEOMETRY_ONLY = AugmentConfig(
    enabled=True, p_photometric=0, p_blur=0, p_noise=0, p_jpeg=0, p_scale_crop=1, zoom=[0.8, 1.25], shift=0.15
)
PHOTOMETRIC_ONLY = AugmentConfig(
    enabled=True, p_photometric=1, p_greyscale=0.3, p_blur=1, p_noise=1, p_jpeg=1, p_scale_crop=0
)


def _rgb(images: torch.Tensor) -> np.ndarray:
    """(V, 3, h, w) normalised -> (V, h, w, 3) float grey levels 0..255."""
    return (images.numpy().transpose(0, 2, 3, 1) * STD + MEAN) * 255.0


def _bilinear(img: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """(h, w, 3) image sampled at (N, 2) pixel-centre coordinates -> (N, 3)."""
    u0, v0 = np.floor(uv[:, 0]).astype(int), np.floor(uv[:, 1]).astype(int)
    a, b = (uv[:, 0] - u0)[:, None], (uv[:, 1] - v0)[:, None]
    return (
        (1 - a) * (1 - b) * img[v0, u0]
        + a * (1 - b) * img[v0, u0 + 1]
        + (1 - a) * b * img[v0 + 1, u0]
        + a * b * img[v0 + 1, u0 + 1]
    )


def test_scale_crop_keeps_foot_points_on_their_cells_and_content(matrix_sample):
    data = BevFrames(matrix_sample, SETTINGS, frames=[FRAME], augment=GEOMETRY_ONLY)
    clean = data.inputs(FRAME)
    aug = data.inputs(FRAME, np.random.default_rng(7))
    clean_img, aug_img = _rgb(clean['images']), _rgb(aug['images'])
    feet = np.array(list(ground_truth_positions(data.dataset, FRAME).values()))  # (N, 2) metres
    cells = apply_homography(np.linalg.inv(data.grid.ground_H_grid), feet)  # (N, 2) grid
    input_H_feat = pixel_scale_homography(data.stride, data.stride)
    img_H_input = pixel_scale_homography(*(np.array(data.dataset.image_size) / data.input_size))
    w, h = data.input_size
    checked, moved, errors, wrong = 0, [], [], []
    for i, view in enumerate(data.views):
        H_clean = clean['feat_H_grid'][i].numpy().astype(np.float64)
        H_aug = aug['feat_H_grid'][i].numpy().astype(np.float64)
        assert not np.allclose(H_clean, H_aug)
        # the clean homography agrees with the camera (independent of feat_H_grid's composition)
        cam_input = apply_homography(np.linalg.inv(img_H_input) @ data.dataset.camera(view, FRAME).img_H_ground(), feet)
        p_clean = apply_homography(input_H_feat @ H_clean, cells)
        np.testing.assert_allclose(p_clean, cam_input, atol=0.05)
        # where the augmented homography puts the feet in the augmented image
        p_aug = apply_homography(input_H_feat @ H_aug, cells)
        inside = np.ones(len(cells), bool)
        for p in (p_aug, p_clean):
            inside &= ((p >= 1) & (p <= (w - 2, h - 2))).all(1)
        if not inside.any():
            continue
        # ... lifts back to the foot's own BEV cell through the inverse of the new feat_H_grid
        back = apply_homography(np.linalg.inv(H_aug) @ np.linalg.inv(input_H_feat), p_aug[inside])
        np.testing.assert_allclose(back, cells[inside], atol=1e-3)
        # ... and shows the same content: the nearest augmented pixel against the clean image at the
        # ground point that pixel lifts to (exact up to the warp's rounding)
        q = np.round(p_aug[inside])
        src = apply_homography(input_H_feat @ H_clean @ np.linalg.inv(H_aug) @ np.linalg.inv(input_H_feat), q)
        errors.append(np.abs(aug_img[i][q[:, 1].astype(int), q[:, 0].astype(int)] - _bilinear(clean_img[i], src)))
        # the old homography would be wrong: the test has the power to see a stale feat_H_grid
        stale = np.round(p_clean[inside])
        wrong.append(
            np.abs(
                aug_img[i][stale[:, 1].astype(int), stale[:, 0].astype(int)]
                - clean_img[i][stale[:, 1].astype(int), stale[:, 0].astype(int)]
            )
        )
        moved.append(np.linalg.norm(p_aug[inside] - p_clean[inside], axis=1))
        checked += int(inside.sum())
    errors, wrong, moved = np.concatenate(errors), np.concatenate(wrong), np.concatenate(moved)
    print(
        f'{checked} foot points; moved median {np.median(moved):.1f} px; content error mean '
        f'{errors.mean():.2f} max {errors.max():.1f}; stale homography mean {wrong.mean():.1f}'
    )
    assert checked >= 40 and np.median(moved) > 5.0  # a strong transform, many points
    assert errors.mean() < 1.0 and errors.max() < 3.0
    assert wrong.mean() > 5 * errors.mean() + 5.0


def test_scale_crop_pads_with_the_normalised_zero(matrix_sample):
    data = BevFrames(
        matrix_sample,
        SETTINGS,
        frames=[FRAME],
        augment=AugmentConfig(
            enabled=True, p_photometric=0, p_blur=0, p_noise=0, p_jpeg=0, p_scale_crop=1, zoom=[0.8, 0.8], shift=0
        ),
    )
    images = data.inputs(FRAME, np.random.default_rng(0))['images']
    assert np.abs(images[:, :, :4, :].numpy()).max() < 0.03  # zoomed out: a padded border, ~0 input
    assert np.allclose(np.array(PAD_RGB) / 255.0, MEAN)


def test_photometric_changes_keep_the_homography(matrix_sample):
    data = BevFrames(matrix_sample, SETTINGS, frames=[FRAME], augment=PHOTOMETRIC_ONLY)
    clean, aug = data.inputs(FRAME), data.inputs(FRAME, np.random.default_rng(3))
    assert torch.equal(clean['feat_H_grid'], aug['feat_H_grid'])
    assert torch.equal(clean['view_mask'], aug['view_mask'])
    diff = (_rgb(clean['images']) - _rgb(aug['images'])).reshape(len(data.views), -1)
    assert (np.abs(diff).mean(1) > 2.0).all()  # every view changed
    rgb = data.rgb(data.views[0], FRAME)
    out = photometric(rgb, PHOTOMETRIC_ONLY, np.random.default_rng(1))
    assert out.shape == rgb.shape and out.dtype == np.uint8


def test_augmentation_is_deterministic_per_seed(matrix_sample):
    config = AugmentConfig(enabled=True, p_photometric=1, p_blur=1, p_noise=1, p_jpeg=1, p_scale_crop=1)
    data = BevFrames(matrix_sample, SETTINGS, frames=[FRAME - 1, FRAME], augment=config)
    a, b = data.sample(1, np.random.default_rng(5)), data.sample(1, np.random.default_rng(5))
    c = data.sample(1, np.random.default_rng(6))
    for key in ('images', 'feat_H_grid'):
        assert torch.equal(a[key], b[key]) and not torch.equal(a[key], c[key])
    # the epoch generator of training hands each sample a generator of its own, reproducibly
    r1, r2 = np.random.default_rng(0), np.random.default_rng(0)
    assert torch.equal(data.sample(1, augment_rng(data, r1))['images'], data.sample(1, augment_rng(data, r2))['images'])
    assert r1.bit_generator.state == r2.bit_generator.state


def test_disabled_is_identical_to_no_augmentation(matrix_sample):
    plain = BevFrames(matrix_sample, SETTINGS, frames=[FRAME - 1, FRAME])
    off = BevFrames(matrix_sample, SETTINGS, frames=[FRAME - 1, FRAME], augment=AugmentConfig(enabled=False))
    on = BevFrames(matrix_sample, SETTINGS, frames=[FRAME - 1, FRAME], augment=GEOMETRY_ONLY)
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    assert off.augment is None and augment_rng(off, rng) is None and rng.bit_generator.state == state
    expected = plain[1]
    for got in (off.sample(1, np.random.default_rng(1)), on[1], on.sample(1)):  # no generator: clean
        for key, value in expected.items():
            assert torch.equal(got[key], value) if isinstance(value, torch.Tensor) else got[key] == value


def test_augment_config_in_the_training_yaml(tmp_path):
    assert TrainConfig(train=[SequenceSpec('x')]).augment.enabled is False
    cfg = tmp_path / 'c.yaml'
    cfg.write_text('train: [{path: x}]\naugment: {enabled: true, p_jpeg: 0.5, zoom: [0.9, 1.1]}\n')
    aug = load_config(cfg).augment
    assert aug.enabled and aug.p_jpeg == 0.5 and aug.zoom == [0.9, 1.1] and aug.p_blur == AugmentConfig().p_blur
    cfg.write_text('train: [{path: x}]\naugment: {enabled: true, p_jpge: 0.5}\n')
    with pytest.raises(ValueError, match='p_jpge'):
        load_config(cfg)
    with pytest.raises(ValueError, match='probabilities'):
        AugmentConfig(p_noise=1.5)
    with pytest.raises(ValueError, match='zoom'):
        AugmentConfig(zoom=[1.2, 0.9])


def test_training_step_with_augmentation(matrix_sample):
    """Augmented training samples (current and previous frame) go through the model; same seed, same loss."""
    from matrix_core.bev.registry import build_model
    from matrix_core.bev.training import open_sequences, training_step

    torch.set_num_threads(1)
    bev = BevSettings(model='bev_tiny', image_width=160, image_height=96, cell_m=0.5)
    config = TrainConfig(
        train=[SequenceSpec(str(matrix_sample), frames=[1, 2])],
        bev=bev,
        augment=AugmentConfig(enabled=True, p_scale_crop=1, p_photometric=1),
    )
    train_seq, val_seq = open_sequences(config.train, config, training=True), open_sequences(config.train, config)
    assert train_seq[0].augment is config.augment and val_seq[0].augment is None
    torch.manual_seed(0)
    model = build_model('bev_tiny').eval()
    with torch.no_grad():
        a, b = (training_step(model, train_seq, [(0, 1)], config, np.random.default_rng(4))['total'] for _ in '12')
        clean = training_step(model, val_seq, [(0, 1)], config, np.random.default_rng(4))['total']
    assert torch.isfinite(a) and float(a) == float(b) and float(a) != float(clean)
