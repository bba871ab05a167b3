"""Symmetric nearest-neighbour matching with Lowe's ratio test.

A pair (i, j) is kept only if j is i's nearest neighbour in ``b``, i is j's nearest neighbour in ``a``
(mutual best), and both directions pass the ratio test ``d1 < ratio * d2`` (L2 distances).

Methods: ``brute`` (exact: one matrix of squared distances, from a matrix product, gives both directions at
once; the same pairs as OpenCV's brute-force matcher run both ways) and ``flann`` (OpenCV KD-trees,
approximate: each direction builds its trees again). On real MATRIX SIFT features (1500-2000 per frame
against 1700-2400 of the reference, one thread) brute takes 20-35 ms where flann takes 38-53 ms; with more
BLAS threads than free cores the product's spinning threads cost more than it saves (the nodes use one:
``NodeSettings.apply_threads``).
"""

import cv2
import numpy as np

# Rows of the distance matrix computed at once: bounds the memory (a few BLOCK x Nb float32 arrays, 33 MB
# each against a 16000-feature reference).
BLOCK = 512


def _two_smallest(d: np.ndarray, axis: int):
    """Index of the smallest value along ``axis`` and the smallest and second-smallest values, each 1-D.
    ``d`` is modified (its minima set to inf)."""
    best = np.argmin(d, axis=axis)
    other = np.arange(d.shape[1 - axis])
    at = (other, best) if axis == 1 else (best, other)
    first = d[at].copy()
    d[at] = np.inf
    return best, first, d.min(axis=axis)


def _mutual_exact(a: np.ndarray, b: np.ndarray):
    """Exact nearest neighbours both ways from squared L2 distances ``|a|^2 + |b|^2 - 2 a.b``, in row blocks.

    Returns ((Na,) nearest b of each a, its squared distance, the second-nearest's), and the same (Nb,)
    triple for b in a.
    """
    a = np.ascontiguousarray(a, np.float32)
    b = np.ascontiguousarray(b, np.float32)
    bb = np.einsum('ij,ij->i', b, b)
    ab, ab1, ab2 = (np.empty(len(a), np.int64), np.empty(len(a), np.float32), np.empty(len(a), np.float32))
    ba, ba1, ba2 = np.full(len(b), -1), np.full(len(b), np.inf, np.float32), np.full(len(b), np.inf, np.float32)
    for lo in range(0, len(a), BLOCK):
        blk = a[lo : lo + BLOCK]
        d = np.einsum('ij,ij->i', blk, blk)[:, None] + bb[None, :] - 2.0 * (blk @ b.T)
        np.maximum(d, 0.0, out=d)
        col = d.copy()  # the row search marks its minima in d
        ab[lo : lo + len(blk)], ab1[lo : lo + len(blk)], ab2[lo : lo + len(blk)] = _two_smallest(d, axis=1)
        if len(blk) < 2:  # one row: its value is every column's best here; the second stays the running one
            best, first, second = np.zeros(len(b), np.int64), col[0], np.full(len(b), np.inf, np.float32)
        else:
            best, first, second = _two_smallest(col, axis=0)
        # merge this block's two smallest per column with the running two smallest
        better = first < ba1
        ba2 = np.where(better, np.minimum(ba1, second), np.minimum(ba2, first))
        ba = np.where(better, best + lo, ba)
        ba1 = np.where(better, first, ba1)
    return (ab, ab1, ab2), (ba, ba1, ba2)


def _knn2(query: np.ndarray, train: np.ndarray, method: str):
    """For each query row: (nearest train index, nearest distance, second-nearest distance), each (N,)."""
    n = len(query)
    if n == 0 or len(train) < 2:
        return np.full(n, -1), np.full(n, np.inf), np.full(n, np.inf)
    if method != 'flann':
        raise ValueError(f'unknown matcher {method!r} (flann or brute)')
    matcher = cv2.FlannBasedMatcher({'algorithm': 1, 'trees': 4}, {'checks': 64})
    pairs = matcher.knnMatch(np.ascontiguousarray(query, np.float32), np.ascontiguousarray(train, np.float32), k=2)
    best, d1, d2 = np.full(n, -1), np.full(n, np.inf), np.full(n, np.inf)
    for m in pairs:
        if len(m) == 2:
            best[m[0].queryIdx], d1[m[0].queryIdx], d2[m[0].queryIdx] = m[0].trainIdx, m[0].distance, m[1].distance
    return best, d1, d2


def match_symmetric(desc_a: np.ndarray, desc_b: np.ndarray, ratio: float = 0.8, method: str = 'flann') -> np.ndarray:
    """Mutual-best matches that pass the ratio test in both directions.

    Args:
        desc_a: (Na, D) descriptors of image a; desc_b: (Nb, D) descriptors of image b.
        ratio: Lowe's tau; a direction passes when best distance < ratio * second-best distance.
        method: 'flann' (KD-trees, approximate) or 'brute' (exact, one distance matrix; see the module).

    Returns:
        (M, 2) int array of index pairs (i into a, j into b), sorted by i.
    """
    if method == 'brute':
        if len(desc_a) < 2 or len(desc_b) < 2:
            return np.zeros((0, 2), np.int64)
        (ab, ab1, ab2), (ba, ba1, ba2) = _mutual_exact(desc_a, desc_b)
        r2 = ratio * ratio  # squared distances: d1 < ratio * d2  <=>  d1^2 < ratio^2 * d2^2
        i = np.flatnonzero(ab1 < r2 * ab2)
        keep = (ba[ab[i]] == i) & (ba1[ab[i]] < r2 * ba2[ab[i]])
        return np.stack([i[keep], ab[i][keep]], axis=1).astype(np.int64).reshape(-1, 2)
    ab, ab1, ab2 = _knn2(desc_a, desc_b, method)
    i = np.flatnonzero((ab >= 0) & (ab1 < ratio * ab2))
    # The way back is needed only from the b features that some a feature chose (fewer queries, same pairs).
    chosen = np.unique(ab[i])
    ba, ba1, ba2 = _knn2(np.asarray(desc_b)[chosen], desc_a, method)
    k = np.searchsorted(chosen, ab[i])
    keep = (ba[k] == i) & (ba1[k] < ratio * ba2[k])
    return np.stack([i[keep], ab[i][keep]], axis=1).astype(np.int64).reshape(-1, 2)
