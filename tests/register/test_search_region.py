"""The anchor after a doubted chain describes features only where the chain's prediction puts the reference's
ground (register/search_region.py), on the real MATRIX sample, and falls back to the whole image when that
does not register."""

import time

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register.backend_sift import SiftBackend
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.features import to_full_resolution
from matrix_core.register.ground_mask import ground_mask, ground_pixels
from matrix_core.register.registrar import Registrar
from matrix_core.register.search_region import predicted_region
from matrix_core.register.settings import MATRIX_BLOCK, RegisterSettings

TRACK = RegisterSettings(mode='track')


@pytest.fixture(scope='module')
def dataset(matrix_sample):
    cv2.setNumThreads(1)
    return MatrixDataset(matrix_sample)


def test_ground_mask_is_ground_pixels_at_the_reduced_pixel_centres(dataset):
    cam = dataset.reference_camera('D1')
    mask = ground_mask(cam, 0.25, dataset.area, 0.0, MATRIX_BLOCK)
    assert mask.shape == (270, 480) and 0.2 < mask.mean() < 0.8
    rng = np.random.default_rng(0)
    uv = np.column_stack([rng.integers(0, 480, 200), rng.integers(0, 270, 200)])
    expected = ground_pixels(cam, to_full_resolution(uv, 0.25), dataset.area, 0.0, MATRIX_BLOCK)
    assert np.array_equal(mask[uv[:, 1], uv[:, 0]], expected)


def test_predicted_region_follows_the_prediction_and_grows_by_the_margin():
    mask = np.zeros((270, 480), bool)
    mask[100:150, 200:300] = True
    assert np.array_equal(predicted_region(mask, np.eye(3), 0.25, 0.0), mask)
    # current -> reference moves 80 full px right and 40 down: the ground sits 20 and 10 reduced px up-left
    shifted = predicted_region(mask, np.array([[1, 0, 80.0], [0, 1, 40.0], [0, 0, 1]]), 0.25, 0.0)
    rows, cols = np.flatnonzero(shifted.any(axis=1)), np.flatnonzero(shifted.any(axis=0))
    assert (rows[0], rows[-1], cols[0], cols[-1]) == (90, 139, 180, 279)
    grown = predicted_region(mask, np.eye(3), 0.25, 40.0)  # 10 reduced px on every side
    rows, cols = np.flatnonzero(grown.any(axis=1)), np.flatnonzero(grown.any(axis=0))
    assert (rows[0], rows[-1], cols[0], cols[-1]) == (90, 159, 190, 309)


def test_sift_with_a_mask_describes_only_inside_it_and_costs_less(dataset):
    image = dataset.load_image('D1', 2)
    sift = SiftBackend(0.25, TRACK.contrast_threshold)
    everywhere = sift.extract(image, 4000)
    mask = ground_mask(dataset.camera('D1', 2), 0.25, dataset.area, 0.0, MATRIX_BLOCK)
    inside = sift.extract(image, 4000, mask)
    uv = np.round((inside.xy + 0.5) * 0.25 - 0.5).astype(int)
    assert 100 < len(inside) < 0.8 * len(everywhere)
    assert mask[uv[:, 1], uv[:, 0]].all()
    # Away from the crop's edge the features are those of the whole image (the same pyramid there).
    d = np.linalg.norm(inside.xy[:, None] - everywhere.xy[None], axis=2).min(axis=1)
    assert np.mean(d < 0.5) > 0.8
    # An all-true mask is the whole image; an empty one describes nothing.
    assert np.allclose(sift.extract(image, 4000, np.ones((270, 480), bool)).xy, everywhere.xy)
    assert len(sift.extract(image, 4000, np.zeros((270, 480), bool))) == 0


def _run(dataset, view, settings=TRACK):
    ref = dataset.reference_camera(view)
    registrar = Registrar(settings, dataset.reference_image(view), ref, dataset.area, f'{view}/reference')
    out = []
    for frame in dataset.frames:
        r = registrar.register(dataset.load_image(view, frame), frame)
        out.append(
            (
                r,
                homography_error_px(r.ref_H_img, dataset.camera(view, frame), ref, dataset.area, MATRIX_BLOCK)
                if r.ok
                else None,
            )
        )
    return registrar, out


def test_doubted_chains_anchor_within_the_predicted_ground(dataset):
    """D2's chain is doubted on frames 1-3 (5-26 refined inliers, fewer than track_min_inliers)."""
    _, results = _run(dataset, 'D2')
    doubted = [(r, e) for r, e in results if r.message.startswith('anchor: chain doubted')]
    assert len(doubted) >= 2, [r.message for r, _ in results]
    for r, error in doubted:
        assert r.ok and 'features within the predicted ground' in r.message, r.message
        assert error < 1.0, f'{r.message}: {error:.2f} px'
    # The first frame has no prediction: the whole image.
    assert 'predicted ground' not in results[0][0].message
    _, unmasked = _run(dataset, 'D2', RegisterSettings(mode='track', anchor_search_margin_px=0.0))
    assert not any('predicted ground' in r.message for r, _ in unmasked)
    assert np.median([e for _, e in results]) <= np.median([e for _, e in unmasked]) + 0.05


def test_a_wrong_prediction_falls_back_to_the_whole_image(dataset):
    registrar, _ = _run(dataset, 'D2')
    sky = np.zeros((270, 480), bool)
    sky[:40] = True  # where the reference's ground is not: nothing there registers
    r = registrar._register_full(dataset.load_image('D2', 4), 4, time.perf_counter(), sky)
    assert r.ok and 'not registered within the predicted ground' in r.message, r.message
    error = homography_error_px(
        r.ref_H_img, dataset.camera('D2', 4), dataset.reference_camera('D2'), dataset.area, MATRIX_BLOCK
    )
    assert error < 1.0


def test_the_margin_is_checked():
    with pytest.raises(ValueError, match='anchor_search_margin_px'):
        RegisterSettings(anchor_search_margin_px=-1.0)
