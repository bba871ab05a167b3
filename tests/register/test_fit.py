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
    fit = fit_homography(src, src * 2.0 + 1.0)
    assert fit.H is None and fit.reason
    assert not fit.inliers.any()


def test_nan_coordinates_and_too_few_points_fail():
    src = np.array([[0, 0], [1, 0], [0, 1], [1, 1], [2, 3]], float)
    bad = src.copy()
    bad[2, 0] = np.nan
    assert 'NaN' in fit_homography(bad, src).reason
    assert 'need 4' in fit_homography(src[:3], src[:3]).reason


@pytest.mark.parametrize('H, words', [
    (np.full((3, 3), np.nan), 'NaN'),
    (np.array([[1, 0, 0], [0, 1, 0], [0, 0, 0.0]]), 'H[2,2] = 0'),
    (np.array([[1, 2, 3], [2, 4, 6], [0, 0, 1.0]]), 'singular'),
])
def test_invalid_homographies_are_named(H, words):
    assert words in is_valid_homography(H)
    assert is_valid_homography(np.eye(3)) == ''
