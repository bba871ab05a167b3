"""Symmetric ratio-test matching on hand-made descriptors (both the exact and the FLANN search), and the exact
search against OpenCV's brute-force matcher on real SIFT features."""

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register import matching
from matrix_core.register.backend_sift import SiftBackend
from matrix_core.register.matching import match_symmetric

METHODS = ('brute', 'flann')


def _pairs(a, b, ratio=0.8, method='brute'):
    return {tuple(p) for p in match_symmetric(np.array(a, np.float32), np.array(b, np.float32), ratio, method)}


@pytest.mark.parametrize('method', METHODS)
def test_distinct_mutual_best_pairs_are_kept(method):
    a = [[0, 0], [10, 0], [0, 10]]
    b = [[0, 10.2], [0.1, 0], [10, 0.3]]
    assert _pairs(a, b, method=method) == {(0, 1), (1, 2), (2, 0)}


@pytest.mark.parametrize('method', METHODS)
def test_ratio_test_rejects_an_ambiguous_query(method):
    # a[0] has two almost equally close candidates (1.0 and 1.1 away): 1.0 / 1.1 > 0.8.
    a = [[0, 0], [20, 20]]
    b = [[1, 0], [-1.1, 0], [20, 20.1]]
    assert _pairs(a, b, method=method) == {(1, 2)}
    # With a looser tau the same pair passes: the test really is the ratio.
    assert (0, 0) in _pairs(a, b, ratio=0.95, method=method)


@pytest.mark.parametrize('method', METHODS)
def test_ratio_test_applies_in_the_reverse_direction_too(method):
    # a[0] -> b[0] is unambiguous (b[1] is far) and mutual, but b[0] sees a[0] and a[1] almost equally
    # close: the reverse ratio test rejects the pair.
    a = [[0, 0], [2.1, 0], [30, 0]]
    b = [[1, 0], [30, 0.2]]
    assert (0, 0) not in _pairs(a, b, method=method)
    assert (2, 1) in _pairs(a, b, method=method)


@pytest.mark.parametrize('method', METHODS)
def test_symmetric_check_rejects_a_non_mutual_best(method):
    # a[0]'s best is b[0] (2 away, next 10 away: passes the ratio), but b[0]'s best is a[1] (0.5 away).
    a = [[0, 0], [2.4, 0], [50, 50]]
    b = [[2, 0], [-8, 0], [50, 51]]
    pairs = _pairs(a, b, ratio=1.0, method=method)
    assert (0, 0) not in pairs
    assert (1, 0) in pairs and (2, 2) in pairs


def test_empty_and_tiny_inputs_give_no_matches():
    assert match_symmetric(np.zeros((0, 8), np.float32), np.ones((5, 8), np.float32)).shape == (0, 2)
    assert match_symmetric(np.ones((5, 8), np.float32), np.ones((1, 8), np.float32)).shape == (0, 2)


def _reference_brute(a, b, ratio):
    """The definition, with OpenCV's brute-force matcher run both ways (what 'brute' computed before)."""

    def knn2(query, train):
        pairs = cv2.BFMatcher(cv2.NORM_L2).knnMatch(query, train, k=2)
        return (
            np.array([m[0].trainIdx for m in pairs]),
            np.array([m[0].distance for m in pairs]),
            np.array([m[1].distance for m in pairs]),
        )

    ab, ab1, ab2 = knn2(a, b)
    ba, ba1, ba2 = knn2(b, a)
    return {(i, j) for i, j in enumerate(ab) if ab1[i] < ratio * ab2[i] and ba[j] == i and ba1[j] < ratio * ba2[j]}


@pytest.mark.parametrize('block', [matching.BLOCK, 97])  # 97: many blocks, the last one short
def test_exact_matching_of_real_sift_features_equals_opencv_brute_force(matrix_sample, monkeypatch, block):
    # Real descriptors (a drone frame and its reference, as the registrar matches them) have many close
    # candidates: the one-matrix search must find the same neighbours both ways as the definition.
    monkeypatch.setattr(matching, 'BLOCK', block)
    dataset = MatrixDataset(matrix_sample)
    sift = SiftBackend(scale=0.25, contrast_threshold=0.005)
    cur = sift.extract(cv2.imread(str(dataset.image_path('D3', 2))), 4000).desc
    ref = sift.extract(dataset.reference_image('D3'), 16000).desc
    pairs = {tuple(p) for p in match_symmetric(cur, ref, 0.8, 'brute')}
    assert len(pairs) > 50  # a real registration's worth, so the comparison means something
    assert pairs == _reference_brute(cur, ref, 0.8)


def test_exact_matching_handles_a_single_row_block(monkeypatch):
    # 5 query rows in blocks of 2: the last block has one row, whose distances are every column's best there.
    monkeypatch.setattr(matching, 'BLOCK', 2)
    rng = np.random.default_rng(0)
    b = rng.normal(size=(7, 16)).astype(np.float32)
    a = (b[[3, 0, 5, 1, 6]] + 0.01 * rng.normal(size=(5, 16))).astype(np.float32)
    assert {tuple(p) for p in match_symmetric(a, b, 0.8, 'brute')} == {(0, 3), (1, 0), (2, 5), (3, 1), (4, 6)}
