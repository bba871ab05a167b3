"""Tracking metrics on the ground plane: CLEAR MOT (MOTA, MOTP), ID measures (IDF1), MT/ML, switches,
fragmentations.

Convention: distances in metres, a ground-truth/track pair may match when at most ``gate`` metres apart
(1 m in the TrackTacular protocol). The per-frame matching follows CLEAR MOT exactly as py-motmetrics
implements it (so the numbers agree with it): pairs matched in the previous frame that are still within
the gate are kept, the rest are assigned by the Hungarian method on distance; a ground-truth id matched
to a different track than at its last match is an ID switch. IDF1 uses the global identity assignment
over all frames (Ristani et al. 2016). A ground-truth id is mostly tracked (MT) when it is matched in
>= 80 % of the frames it appears in, mostly lost (ML) below 20 %. A fragmentation is each change from
matched to unmatched between an id's first and last match.
"""

from dataclasses import asdict, dataclass

import numpy as np

from matrix_core.metrics.assignment import gated_distances, min_cost_matching
from matrix_core.metrics.bev_points import BevPoints


@dataclass(frozen=True)
class TrackingMetrics:
    """Sequence totals; rates are fractions (0..1).

    Attributes:
        mota: 1 - (FN + FP + IDs) / num_gt.
        motp_m: mean distance of matched pairs in metres (py-motmetrics' MOTP with Euclidean distances).
        motp_percent: TrackTacular's form, 100 * (1 - motp_m / gate).
        idf1, idp, idr: ID F1, precision and recall.
        mostly_tracked, partially_tracked, mostly_lost: numbers of ground-truth ids.
        id_switches, fragmentations, fp, fn, matches: event counts.
    """

    mota: float
    motp_m: float
    motp_percent: float
    idf1: float
    idp: float
    idr: float
    precision: float
    recall: float
    mostly_tracked: int
    partially_tracked: int
    mostly_lost: int
    num_gt_ids: int
    id_switches: int
    fragmentations: int
    fp: int
    fn: int
    matches: int
    num_gt: int
    num_pred: int
    num_frames: int
    gate: float

    def as_dict(self) -> dict:
        return asdict(self)


def _ratio(num: float, den: float) -> float:
    return float(num) / float(den) if den else float('nan')


def tracking_metrics(gt: BevPoints, pred: BevPoints, gate: float = 1.0, costs=None) -> TrackingMetrics:
    """CLEAR MOT and ID metrics of the tracks ``pred`` against ``gt`` (both need ids).

    Rows of one frame are processed in file order (which only matters for exact ties).

    Args:
        costs: optional ``costs(gt_rows, pred_rows) -> (n, m)`` pair costs, NaN where a pair may not match,
            for other kinds of objects with ``frames``, ``ids`` and ``by_frame()`` (image boxes:
            ``metrics.image_boxes``); default: ground distances gated at ``gate``. MOTP is the mean cost.
    """
    if not gt.has_ids or not pred.has_ids:
        raise ValueError('tracking metrics need ids in both ground truth and predictions ("frame id x y")')
    if not gate > 0:
        raise ValueError(f'gate must be positive, got {gate}')
    gt_rows, pred_rows = gt.by_frame(), pred.by_frame()
    frames = sorted(set(gt_rows) | set(pred_rows))
    last_match = {}  # gt id -> track id it was matched to most recently
    matched_frames = {}  # gt id -> list of bools, one per appearance
    within_gate = {}  # (gt id, track id) -> frames with distance <= gate (for IDF1)
    fp = fn = switches = matches = 0
    dist_sum = 0.0
    empty = np.zeros(0, dtype=int)
    for f in frames:
        g, p = gt_rows.get(f, empty), pred_rows.get(f, empty)
        oids, hids = gt.ids[g], pred.ids[p]
        d = costs(g, p) if costs is not None else gated_distances(gt.xy[g], pred.xy[p], gate)
        for i, j in zip(*np.nonzero(np.isfinite(d))):
            key = (int(oids[i]), int(hids[j]))
            within_gate[key] = within_gate.get(key, 0) + 1
        o_done = np.zeros(len(g), dtype=bool)
        h_done = np.zeros(len(p), dtype=bool)
        # 1. keep last frame's correspondences that are still within the gate
        for i, o in enumerate(oids):
            if int(o) not in last_match:
                continue
            js = np.flatnonzero(~h_done & (hids == last_match[int(o)]))
            if len(js) and np.isfinite(d[i, js[0]]):
                o_done[i] = h_done[js[0]] = True
                matches += 1
                dist_sum += d[i, js[0]]
        # 2. Hungarian on the rest; a new partner for a previously matched id is a switch
        rest = d.copy()
        rest[o_done, :] = np.nan
        rest[:, h_done] = np.nan
        for i, j in zip(*min_cost_matching(rest)):
            o, h = int(oids[i]), int(hids[j])
            if o in last_match and last_match[o] != h:
                switches += 1
            else:
                matches += 1
            last_match[o] = h
            o_done[i] = h_done[j] = True
            dist_sum += d[i, j]
        fn += int((~o_done).sum())
        fp += int((~h_done).sum())
        for i, o in enumerate(oids):
            matched_frames.setdefault(int(o), []).append(bool(o_done[i]))

    ratios = {o: np.mean(m) for o, m in matched_frames.items()}
    frag = 0
    for m in matched_frames.values():
        hit = np.flatnonzero(m)
        if len(hit):
            span = np.asarray(m[hit[0] : hit[-1] + 1], dtype=int)
            frag += int(np.sum(np.diff(span) == -1))
    idtp = _global_id_true_positives(gt, pred, within_gate)
    detections = matches + switches
    motp = _ratio(dist_sum, detections)
    return TrackingMetrics(
        mota=1.0 - _ratio(fn + fp + switches, len(gt)),
        motp_m=float(motp),
        motp_percent=float(100.0 * (1.0 - motp / gate)),
        idf1=_ratio(2 * idtp, len(gt) + len(pred)),
        idp=_ratio(idtp, len(pred)),
        idr=_ratio(idtp, len(gt)),
        precision=_ratio(detections, detections + fp),
        recall=_ratio(detections, len(gt)),
        mostly_tracked=int(sum(r >= 0.8 for r in ratios.values())),
        partially_tracked=int(sum(0.2 <= r < 0.8 for r in ratios.values())),
        mostly_lost=int(sum(r < 0.2 for r in ratios.values())),
        num_gt_ids=len(ratios),
        id_switches=switches,
        fragmentations=frag,
        fp=fp,
        fn=fn,
        matches=matches,
        num_gt=len(gt),
        num_pred=len(pred),
        num_frames=len(frames),
        gate=gate,
    )


def _global_id_true_positives(gt: BevPoints, pred: BevPoints, within_gate: dict) -> int:
    """IDTP of the best one-to-one identity assignment over the whole sequence.

    Each gt id may be paired with at most one track id (or none); a pair earns the frames in which the
    two are within the gate. Maximising the total is the min-cost problem of Ristani et al.
    """
    oids, hids = np.unique(gt.ids), np.unique(pred.ids)
    if not len(oids) or not len(hids) or not within_gate:
        return 0
    oi = {int(o): k for k, o in enumerate(oids)}
    hi = {int(h): k for k, h in enumerate(hids)}
    gain = np.zeros((len(oids), len(hids)))
    for (o, h), n in within_gate.items():
        gain[oi[o], hi[h]] = n
    rows, cols = min_cost_matching(-gain)
    return int(gain[rows, cols].sum())
