"""Gated minimum-cost matching of ground-plane points (the Hungarian step of every metric here)."""

import numpy as np
from scipy.optimize import linear_sum_assignment


def gated_distances(a_xy: np.ndarray, b_xy: np.ndarray, gate: float) -> np.ndarray:
    """(N, M) Euclidean distances in metres between (N, 2) and (M, 2) points; NaN where distance > ``gate``."""
    a_xy = np.asarray(a_xy, dtype=np.float64).reshape(-1, 2)
    b_xy = np.asarray(b_xy, dtype=np.float64).reshape(-1, 2)
    d = np.linalg.norm(a_xy[:, None, :] - b_xy[None, :, :], axis=2)
    d[d > gate] = np.nan
    return d


def min_cost_matching(costs: np.ndarray) -> tuple:
    """Minimum-cost one-to-one assignment where NaN/inf marks a forbidden pair.

    Forbidden pairs get a cost so large that no optimal solution prefers them (the same construction as
    py-motmetrics' scipy solver, so ties resolve identically), then are dropped from the answer.

    Args:
        costs: (N, M) costs, NaN or inf = may not be paired.

    Returns:
        (rows, cols): int arrays of equal length K <= min(N, M), the admissible pairs.
    """
    costs = np.asarray(costs, dtype=np.float64)
    if costs.size == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    valid = np.isfinite(costs)
    if valid.all():
        finite = costs
    elif not valid.any():
        finite = np.zeros_like(costs)
    else:
        c = np.abs(costs[valid]).max() + 1
        finite = np.where(valid, costs, 2 * min(costs.shape) * c + 1)
    rows, cols = linear_sum_assignment(finite)
    keep = valid[rows, cols]
    return rows[keep].astype(int), cols[keep].astype(int)
