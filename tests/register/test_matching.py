"""Symmetric ratio-test matching on hand-made descriptors (both the exact and the FLANN search)."""

import numpy as np
import pytest

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
