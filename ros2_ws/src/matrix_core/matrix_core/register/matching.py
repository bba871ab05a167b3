"""Symmetric nearest-neighbour matching with Lowe's ratio test.

A pair (i, j) is kept only if j is i's nearest neighbour in ``b``, i is j's nearest neighbour in ``a``
(mutual best), and both directions pass the ratio test ``d1 < ratio * d2`` (L2 distances).
"""

import cv2
import numpy as np


def _knn2(query: np.ndarray, train: np.ndarray, method: str):
    """For each query row: (nearest train index, nearest distance, second-nearest distance), each (N,)."""
    n = len(query)
    if n == 0 or len(train) < 2:
        return np.full(n, -1), np.full(n, np.inf), np.full(n, np.inf)
    if method == 'flann':
        matcher = cv2.FlannBasedMatcher({'algorithm': 1, 'trees': 4}, {'checks': 64})
    elif method == 'brute':
        matcher = cv2.BFMatcher(cv2.NORM_L2)
    else:
        raise ValueError(f'unknown matcher {method!r} (flann or brute)')
    pairs = matcher.knnMatch(np.ascontiguousarray(query, np.float32), np.ascontiguousarray(train, np.float32), k=2)
    best, d1, d2 = np.full(n, -1), np.full(n, np.inf), np.full(n, np.inf)
    for m in pairs:
        if len(m) == 2:
            best[m[0].queryIdx], d1[m[0].queryIdx], d2[m[0].queryIdx] = m[0].trainIdx, m[0].distance, m[1].distance
    return best, d1, d2


def match_symmetric(desc_a: np.ndarray, desc_b: np.ndarray, ratio: float = 0.8,
                    method: str = 'flann') -> np.ndarray:
    """Mutual-best matches that pass the ratio test in both directions.

    Args:
        desc_a: (Na, D) descriptors of image a; desc_b: (Nb, D) descriptors of image b.
        ratio: Lowe's tau; a direction passes when best distance < ratio * second-best distance.
        method: 'flann' (KD-tree, approximate, fast) or 'brute' (exact).

    Returns:
        (M, 2) int array of index pairs (i into a, j into b), sorted by i.
    """
    ab, ab1, ab2 = _knn2(desc_a, desc_b, method)
    i = np.flatnonzero((ab >= 0) & (ab1 < ratio * ab2))
    # The way back is needed only from the b features that some a feature chose (fewer queries, same pairs).
    chosen = np.unique(ab[i])
    ba, ba1, ba2 = _knn2(np.asarray(desc_b)[chosen], desc_a, method)
    k = np.searchsorted(chosen, ab[i])
    keep = (ba[k] == i) & (ba1[k] < ratio * ba2[k])
    return np.stack([i[keep], ab[i][keep]], axis=1).astype(np.int64).reshape(-1, 2)
