"""HOTA (Higher Order Tracking Accuracy, Luiten et al. 2020) on the ground plane, as TrackEval computes it.

Similarity: a ground-truth/track pair of one frame at ``d`` metres has similarity ``S = max(0, 1 - d / gate)``
(``gate`` 1 m, as MOTA's match distance): 1 at the same spot, 0 at the gate and beyond. For each localisation
threshold ``alpha`` in 0.05, 0.10, ..., 0.95 a pair may match when ``S >= alpha``; HOTA and its parts are
computed per alpha and averaged over the 19 alphas.

Per frame, pairs are matched once (Hungarian) by ``A(g, t) * S``, where ``A`` is the global alignment of the
two ids over the whole sequence (Jaccard of their summed soft overlaps), then, for each alpha, the matched
pairs with ``S >= alpha`` are its true positives (TP). With those:
    DetA = TP / (TP + FN + FP), DetRe = TP / (TP + FN), DetPr = TP / (TP + FP);
    AssA = mean over TP of TPA / (TPA + FNA + FPA), where TPA counts the frames the TP's ground-truth id and
    track id are matched, FNA the other frames of the ground-truth id, FPA the other frames of the track;
    AssRe, AssPr likewise with TPA / (TPA + FNA) and TPA / (TPA + FPA);
    HOTA = sqrt(DetA * AssA); LocA = mean S of the TP.
Degenerate inputs follow TrackEval: no ground truth or no track gives 0 everywhere but LocA = 1.
"""

from dataclasses import asdict, dataclass

import numpy as np

from matrix_core.metrics.assignment import gated_distances, min_cost_matching
from matrix_core.metrics.bev_points import BevPoints

# TrackEval's own expression for the thresholds (0.05 ... 0.95), so that a similarity on a threshold
# compares the same way.
ALPHAS = np.arange(0.05, 0.99, 0.05)
_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class HotaMetrics:
    """Sequence values averaged over the alphas; fractions (0..1), not percent.

    Attributes:
        hota: mean over alpha of sqrt(DetA * AssA).
        det_a, det_re, det_pr: detection accuracy, recall, precision.
        ass_a, ass_re, ass_pr: association accuracy, recall, precision.
        loc_a: mean similarity of the true positives (1 - mean distance / gate, roughly).
        num_gt, num_pred: points of ground truth and tracks.  gate: metres where similarity reaches 0.
    """

    hota: float
    det_a: float
    ass_a: float
    det_re: float
    det_pr: float
    ass_re: float
    ass_pr: float
    loc_a: float
    num_gt: int
    num_pred: int
    gate: float

    def as_dict(self) -> dict:
        return asdict(self)


def hota_metrics(gt: BevPoints, pred: BevPoints, gate: float = 1.0) -> HotaMetrics:
    """HOTA, DetA, AssA and their parts of the tracks ``pred`` against ``gt`` (both need ids).

    Args:
        gt: ground truth ``frame id x y`` (world metres).
        pred: tracks ``frame id x y`` (world metres); scores are not used.
        gate: distance in metres at which the similarity falls to 0.
    """
    if not gt.has_ids or not pred.has_ids:
        raise ValueError('HOTA needs ids in both ground truth and predictions ("frame id x y")')
    if not gate > 0:
        raise ValueError(f'gate must be positive, got {gate}')
    n = len(ALPHAS)
    if not len(gt) or not len(pred):
        zero = np.zeros(n)
        return _summary(zero, len(gt) + zero, len(pred) + zero, zero, zero, zero, np.ones(n), gate)
    # ids as 0..G-1 and 0..T-1; a (ground truth, track) pair as the one integer g * T + t
    gt_ids, g_idx = np.unique(gt.ids, return_inverse=True)
    pred_ids, t_idx = np.unique(pred.ids, return_inverse=True)
    n_t = len(pred_ids)
    gt_count = np.bincount(g_idx, minlength=len(gt_ids)).astype(float)
    pred_count = np.bincount(t_idx, minlength=n_t).astype(float)
    frames = _frames(gt, pred, gate)

    # 1. global alignment of every id pair that is ever within the gate
    codes, soft = [], []
    for g, p, s in frames:
        r, c = np.nonzero(s > 0)
        # a pair's share of the similarity of its row and column (TrackEval's soft IoU of one frame)
        denom = s.sum(axis=0)[None, :] + s.sum(axis=1)[:, None] - s
        codes.append(g_idx[g][r] * n_t + t_idx[p][c])
        soft.append(s[r, c] / denom[r, c])
    pairs, inverse = np.unique(np.concatenate(codes), return_inverse=True)
    overlap = np.bincount(inverse, weights=np.concatenate(soft))
    alignment = overlap / (gt_count[pairs // n_t] + pred_count[pairs % n_t] - overlap)

    # 2. one matching per frame by alignment * similarity; each alpha keeps the pairs with S >= alpha
    tp_code, tp_sim = [], []
    for g, p, s in frames:
        if not s.size:
            continue
        code = g_idx[g][:, None] * n_t + t_idx[p][None, :]
        a = np.zeros_like(s)
        if len(pairs):  # pairs never within the gate have alignment 0
            where = np.clip(np.searchsorted(pairs, code), 0, len(pairs) - 1)
            a = np.where((s > 0) & (pairs[where] == code), alignment[where], 0.0)
        rows, cols = min_cost_matching(-(a * s))  # every pair admissible, as TrackEval's assignment
        tp_code.append(code[rows, cols])
        tp_sim.append(s[rows, cols])
    tp_code = np.concatenate(tp_code) if tp_code else np.zeros(0, dtype=np.int64)
    tp_sim = np.concatenate(tp_sim) if tp_sim else np.zeros(0)

    tp, ass_a, ass_re, ass_pr, loc = (np.zeros(n) for _ in range(5))
    for k, alpha in enumerate(ALPHAS):
        hit = tp_sim >= alpha - _EPS
        tp[k] = hit.sum()
        loc[k] = max(1e-10, tp_sim[hit].sum()) / max(1e-10, tp[k])
        matched, count = np.unique(tp_code[hit], return_counts=True)
        g_n, t_n = gt_count[matched // n_t], pred_count[matched % n_t]
        # sum over TP of the per-pair score = sum over pairs of count * score
        ass_a[k] = np.sum(count * count / np.maximum(1, g_n + t_n - count)) / max(1.0, tp[k])
        ass_re[k] = np.sum(count * count / np.maximum(1, g_n)) / max(1.0, tp[k])
        ass_pr[k] = np.sum(count * count / np.maximum(1, t_n)) / max(1.0, tp[k])
    return _summary(tp, len(gt) - tp, len(pred) - tp, ass_a, ass_re, ass_pr, loc, gate)


def _frames(gt: BevPoints, pred: BevPoints, gate: float) -> list:
    """(gt rows, pred rows, (n, m) similarity) of every frame with ground truth or tracks."""
    gt_rows, pred_rows = gt.by_frame(), pred.by_frame()
    empty = np.zeros(0, dtype=int)
    out = []
    for f in sorted(set(gt_rows) | set(pred_rows)):
        g, p = gt_rows.get(f, empty), pred_rows.get(f, empty)
        d = gated_distances(gt.xy[g], pred.xy[p], gate)  # NaN beyond the gate: similarity 0
        out.append((g, p, np.where(np.isnan(d), 0.0, 1.0 - d / gate)))
    return out


def _summary(tp, fn, fp, ass_a, ass_re, ass_pr, loc_a, gate: float) -> HotaMetrics:
    """The alpha-averaged values from (19,) per-alpha counts and association scores."""
    det_a = tp / np.maximum(1, tp + fn + fp)
    return HotaMetrics(
        hota=float(np.mean(np.sqrt(det_a * ass_a))),
        det_a=float(np.mean(det_a)),
        ass_a=float(np.mean(ass_a)),
        det_re=float(np.mean(tp / np.maximum(1, tp + fn))),
        det_pr=float(np.mean(tp / np.maximum(1, tp + fp))),
        ass_re=float(np.mean(ass_re)),
        ass_pr=float(np.mean(ass_pr)),
        loc_a=float(np.mean(loc_a)),
        num_gt=int(tp[0] + fn[0]),
        num_pred=int(tp[0] + fp[0]),
        gate=gate,
    )
