"""Cost of pairing tracks with detections and the gated assignment."""

import numpy as np
from scipy.optimize import linear_sum_assignment


def track_gate(track, gate_m: float, gate_growth_m: float = 0.0, max_gate_m: float = None) -> float:
    """Gate radius (m) of ``track``: ``gate_m``, plus ``gate_growth_m`` per frame it has been missed in a row
    (its prediction grows less certain), at most ``max_gate_m`` (None: no limit)."""
    gate = gate_m + gate_growth_m * track.misses
    return gate if max_gate_m is None else min(gate, max(max_gate_m, gate_m))


def association_costs(
    tracks: list,
    dets,
    rows: np.ndarray,
    use_offsets: bool,
    gate_m: float,
    gate_growth_m: float = 0.0,
    max_gate_m: float = None,
) -> np.ndarray:
    """(T, R) costs of pairing ``tracks`` with detections ``dets[rows]``, negative (worth pairing) within a
    track's gate (:func:`track_gate`), NaN beyond it.

    The cost is the negative log-likelihood of the detection under a Gaussian around the track with a
    standard deviation of a third of its gate, relative to a detection at the gate of a track seen in the
    last frame: ``z**2 / 2 + 2 ln(gate / gate_m) - 4.5`` with ``z = 3 d / gate``. So a coasting track, whose
    gate has grown, pays for its spread: of two tracks at the same distance from a detection the one seen
    last frame is the likelier owner, and a coasting track takes a far detection only when no closer track
    can.

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
        gate = track_gate(tr, gate_m, gate_growth_m, max_gate_m)
        z = 3.0 * d / gate
        costs[k] = np.where(d <= gate, z**2 / 2 + 2 * np.log(gate / gate_m) - 4.5, np.nan)
    return costs


def gain_matching(costs: np.ndarray) -> tuple:
    """One-to-one pairs of least total cost over (N, M) ``costs`` (NaN: forbidden), where leaving a track
    or a detection unpaired costs nothing and every allowed pair at least a little less than that.

    Unlike a matching that first maximises the number of pairs at any price, a track does not take a far
    detection (or a false positive) just so that a neighbour can take its own: the swap that changes ids.
    Returns (rows, cols) int arrays of the pairs made.
    """
    costs = np.asarray(costs, dtype=np.float64)
    if costs.size == 0:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    valid = np.isfinite(costs)
    # a forbidden pair costs 0, the same as leaving both unpaired, so the solver may "use" it freely
    gain = np.where(valid, np.minimum(costs, -1e-9), 0.0)
    rows, cols = linear_sum_assignment(gain)
    keep = valid[rows, cols]
    return rows[keep].astype(int), cols[keep].astype(int)


def associate(
    tracks: list,
    dets,
    rows: np.ndarray,
    use_offsets: bool,
    gate_m: float,
    gate_growth_m: float = 0.0,
    max_gate_m: float = None,
) -> tuple:
    """Gated assignment (:func:`gain_matching` of :func:`association_costs`). Returns (pairs [(track
    index, detection row)], unmatched track indices, unmatched detection rows)."""
    r, c = gain_matching(association_costs(tracks, dets, rows, use_offsets, gate_m, gate_growth_m, max_gate_m))
    pairs = [(int(i), int(rows[j])) for i, j in zip(r, c)]
    used_t, used_d = set(r.tolist()), set(c.tolist())
    return (
        pairs,
        [i for i in range(len(tracks)) if i not in used_t],
        np.array([rows[j] for j in range(len(rows)) if j not in used_d], dtype=int),
    )
