"""Multi-view detection metrics on the ground plane: MODA, MODP, precision, recall.

Convention: a prediction is a true positive when the per-frame Hungarian matching (cost = distance)
pairs it with a ground-truth point at most ``threshold`` metres away (0.5 m in the MVDet/EarlyBird/
TrackTacular protocol). Every frame that has ground truth counts its misses, with or without predictions.
"""

from dataclasses import asdict, dataclass

import numpy as np

from matrix_core.metrics.assignment import gated_distances, min_cost_matching
from matrix_core.metrics.bev_points import BevPoints


@dataclass(frozen=True)
class DetectionMetrics:
    """Counts and rates over a whole sequence. Rates are fractions (0..1), not percent.

    Attributes:
        moda: 1 - (FP + FN) / num_gt (can be negative).
        modp: mean of (1 - d / threshold) over true positives (MVDet's MODP; 1 = perfect centring).
        mean_error_m: mean distance in metres of the true positives.
        precision: TP / (TP + FP).  recall: TP / num_gt.
    """

    moda: float
    modp: float
    precision: float
    recall: float
    mean_error_m: float
    tp: int
    fp: int
    fn: int
    num_gt: int
    num_frames: int
    threshold: float

    def as_dict(self) -> dict:
        return asdict(self)


def _ratio(num: float, den: float) -> float:
    return float(num) / float(den) if den else float('nan')


def detection_metrics(gt: BevPoints, pred: BevPoints, threshold: float = 0.5) -> DetectionMetrics:
    """Detection metrics of ``pred`` against ``gt`` (ids, if any, are ignored).

    Args:
        gt: ground-truth positions (world metres).
        pred: predicted positions (world metres); scores are not used (threshold them beforehand).
        threshold: match distance in metres.
    """
    if not threshold > 0:
        raise ValueError(f'threshold must be positive, got {threshold}')
    gt_rows, pred_rows = gt.by_frame(), pred.by_frame()
    frames = sorted(set(gt_rows) | set(pred_rows))
    tp = fp = fn = 0
    dist_sum = 0.0
    for f in frames:
        g = gt_rows.get(f, np.zeros(0, dtype=int))
        p = pred_rows.get(f, np.zeros(0, dtype=int))
        d = gated_distances(gt.xy[g], pred.xy[p], threshold)
        r, c = min_cost_matching(d)
        tp += len(r)
        fn += len(g) - len(r)
        fp += len(p) - len(r)
        dist_sum += float(d[r, c].sum())
    num_gt = len(gt)
    return DetectionMetrics(
        moda=1.0 - _ratio(fp + fn, num_gt),
        modp=_ratio(tp - dist_sum / threshold, tp),
        precision=_ratio(tp, tp + fp),
        recall=_ratio(tp, num_gt),
        mean_error_m=_ratio(dist_sum, tp),
        tp=tp,
        fp=fp,
        fn=fn,
        num_gt=num_gt,
        num_frames=len(frames),
        threshold=threshold,
    )
