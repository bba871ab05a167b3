"""Cost of pairing tracks with detections and the gated Hungarian assignment."""

import numpy as np

from matrix_core.metrics.assignment import min_cost_matching


def association_costs(
    tracks: list, dets, rows: np.ndarray, use_offsets: bool, gate_m: float, gate_growth_m: float = 0.0
) -> np.ndarray:
    """(T, R) distances in metres between ``tracks`` and detections ``dets[rows]``; NaN beyond the gate,
    which is ``gate_m + gate_growth_m * misses`` for a track that missed its last ``misses`` frames.

    A track matched in the previous frame is compared with where the detection says the person WAS
    (``xy + offset``, CenterTrack) against the track's last position; otherwise (no offsets, or the track
    is coasting through a gap) the detection is compared with the Kalman prediction.
    """
    xy = dets.xy[rows]
    costs = np.full((len(tracks), len(rows)), np.nan)
    for k, tr in enumerate(tracks):
        if use_offsets and dets.offsets is not None and tr.misses == 0:
            d = np.linalg.norm(xy + dets.offsets[rows] - tr.last_xy, axis=1)
        else:
            d = np.linalg.norm(xy - tr.xy, axis=1)
        costs[k] = np.where(d <= gate_m + gate_growth_m * tr.misses, d, np.nan)
    return costs


def associate(
    tracks: list, dets, rows: np.ndarray, use_offsets: bool, gate_m: float, gate_growth_m: float = 0.0
) -> tuple:
    """Hungarian matching. Returns (pairs [(track index, detection row)], unmatched track indices,
    unmatched detection rows)."""
    r, c = min_cost_matching(association_costs(tracks, dets, rows, use_offsets, gate_m, gate_growth_m))
    pairs = [(int(i), int(rows[j])) for i, j in zip(r, c)]
    used_t, used_d = set(r.tolist()), set(c.tolist())
    return (
        pairs,
        [i for i in range(len(tracks)) if i not in used_t],
        np.array([rows[j] for j in range(len(rows)) if j not in used_d], dtype=int),
    )
