"""Robust homography fit: exact recovery, and NaN / degenerate / too-few cases reported as failures."""

import numpy as np
import pytest

from matrix_core.register.fit import fit_homography, is_valid_homography


def test_recovers_a_known_homography_with_outliers():
    rng = np.random.default_rng(1)
    H = np.array([[1.1, 0.05, 20.0], [-0.03, 0.95, -15.0], [1e-4, -5e-5, 1.0]])
    src = rng.uniform(0, 1000, (200, 2))
    hom = np.c_[src, np.ones(len(src))] @ H.T
    dst = hom[:, :2] / hom[:, 2:]
    dst[:40] += rng.uniform(30, 80, (40, 2))  # 20 % gross outliers
    for method in ('ransac', 'magsac'):
        fit = fit_homography(src, dst, method, 2.0)
        assert fit.reason == ''
        np.testing.assert_allclose(fit.H, H, rtol=1e-4, atol=1e-6)
        assert fit.inliers[40:].all() and not fit.inliers[:40].any()
        assert fit.error_px < 1e-3


def test_collinear_points_are_degenerate():
    src = np.c_[np.linspace(0, 100, 30), np.linspace(0, 50, 30)]
    for method in ('magsac', 'ransac'):
        fit = fit_homography(src, src * 2.0 + 1.0, method)
        assert fit.H is None and fit.reason
        assert not fit.inliers.any()


def test_nan_coordinates_and_too_few_points_fail():
    src = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 3]], float)
    bad = src.copy()
    bad[2, 0] = np.nan
    assert 'NaN' in fit_homography(bad, src).reason
    assert 'need 4' in fit_homography(src[:3], src[:3]).reason


@pytest.mark.parametrize(
    'H, words',
    [
        (np.full((3, 3), np.nan), 'NaN'),
        (np.array([[1, 0, 0], [0, 1, 0], [0, 0, 0.0]]), 'H[2,2] = 0'),
        (np.array([[1, 2, 3], [2, 4, 6], [0, 0, 1.0]]), 'singular'),
    ],
)
def test_invalid_homographies_are_named(H, words):
    assert words in is_valid_homography(H)
    assert is_valid_homography(np.eye(3)) == ''


@pytest.fixture(scope='module')
def real_matches(matrix_sample):
    """SIFT matches of drone D1's frame 0 to its reference image in the real MATRIX sample: (src, dst)
    full-resolution pixels, as the registrar fits them (ground mask off: more outliers, a harder fit)."""
    import cv2

    from matrix_core.register.backend_sift import SiftBackend
    from matrix_core.register.matching import match_symmetric

    backend = SiftBackend(scale=0.25, contrast_threshold=0.005)
    cur = backend.extract(cv2.imread(str(matrix_sample / 'image_subsets/D1/0000.jpg')), 4000)
    ref_dir = matrix_sample / 'reference/image_subsets/D1'
    ref = backend.extract(cv2.imread(str(sorted(ref_dir.iterdir())[0])), 8000)
    pairs = match_symmetric(cur.desc, ref.desc, 0.8)
    assert len(pairs) > 100
    return cur.xy[pairs[:, 0]], ref.xy[pairs[:, 1]]


def test_plain_ransac_is_seeded_on_a_real_image_pair(real_matches):
    src, dst = real_matches
    fits = [fit_homography(src, dst, 'ransac', 3.0, seed=seed) for seed in range(10)]
    assert all(f.reason == '' for f in fits)
    again = fit_homography(src, dst, 'ransac', 3.0, seed=3)
    np.testing.assert_array_equal(again.H, fits[3].H)  # same seed, same H
    np.testing.assert_array_equal(again.inliers, fits[3].inliers)
    distinct = {f.H.tobytes() for f in fits}
    assert len(distinct) >= 5, f'only {len(distinct)} different homographies from 10 seeds'
    # Different samples, one scene: the homographies agree on where the image centre goes (a few pixels).
    centre = np.array([[[960.0, 540.0]]])
    import cv2

    mapped = np.array([cv2.perspectiveTransform(centre, f.H).ravel() for f in fits])
    assert np.ptp(mapped, axis=0).max() < 30.0


def test_magsac_is_deterministic_whatever_the_seed(real_matches):
    src, dst = real_matches
    a, b = fit_homography(src, dst, 'magsac', 3.0, seed=0), fit_homography(src, dst, 'magsac', 3.0, seed=7)
    assert a.reason == '' and np.array_equal(a.H, b.H)


def test_unknown_estimator_is_an_error():
    with pytest.raises(ValueError, match='estimator'):
        fit_homography(np.zeros((5, 2)), np.zeros((5, 2)), 'lmeds')
