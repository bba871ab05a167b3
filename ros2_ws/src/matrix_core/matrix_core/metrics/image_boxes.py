"""Metrics in the image plane: 2D boxes of every drone against the annotated boxes, with identities.

A predicted box matches an annotated box of the same drone and frame when their IoU is at least
``iou_threshold`` (0.5, the MOT-challenge rule); the per-frame matching and the identity measures are
CLEAR MOT / IDF1 exactly as on the ground plane (:func:`~matrix_core.metrics.tracking.tracking_metrics`, with
cost 1 - IoU). Per drone, each drone's boxes are a sequence of their own; overall, every (frame, drone) is
one step of one sequence, so a person must carry the SAME fused id in every drone to score no switches
(fused ids are global). Boxes: ``x_min y_min x_max y_max`` pixels.

Text form (MOT-challenge style, one box per line, comma separated)::

    frame,id,x,y,w,h,score,drone
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from matrix_core.metrics.bev_points import rows_by_frame
from matrix_core.metrics.tracking import TrackingMetrics, tracking_metrics
from matrix_core.output_paths import atomic_write_text


@dataclass(frozen=True)
class FrameBoxes:
    """N boxes, each in one frame of one drone.

    Attributes:
        frames: (N,) int64; views: (N,) str drone names; ids: (N,) int64 identities;
        boxes: (N, 4) float64 x_min y_min x_max y_max pixels; scores: (N,) float64.
    """

    frames: np.ndarray
    views: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    scores: np.ndarray = None

    def __post_init__(self):
        n = len(np.reshape(self.frames, -1))
        object.__setattr__(self, 'frames', np.asarray(self.frames, dtype=np.int64).reshape(-1))
        object.__setattr__(self, 'views', np.asarray(self.views, dtype=str).reshape(-1))
        object.__setattr__(self, 'ids', np.asarray(self.ids, dtype=np.int64).reshape(-1))
        object.__setattr__(self, 'boxes', np.asarray(self.boxes, dtype=np.float64).reshape(-1, 4))
        object.__setattr__(
            self, 'scores', np.ones(n) if self.scores is None else np.asarray(self.scores, dtype=np.float64).reshape(-1)
        )
        if not (len(self.views) == len(self.ids) == len(self.boxes) == len(self.scores) == n):
            raise ValueError('frames, views, ids, boxes and scores differ in length')

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def has_ids(self) -> bool:
        return True

    def select(self, keep) -> 'FrameBoxes':
        return FrameBoxes(self.frames[keep], self.views[keep], self.ids[keep], self.boxes[keep], self.scores[keep])

    @classmethod
    def concatenate(cls, parts) -> 'FrameBoxes':
        parts = list(parts)
        if not parts:
            return cls(np.zeros(0), np.zeros(0, str), np.zeros(0), np.zeros((0, 4)))
        return cls(
            *(np.concatenate([getattr(p, a) for p in parts]) for a in ('frames', 'views', 'ids', 'boxes', 'scores'))
        )


class _Steps:
    """``frames`` / ``ids`` / ``by_frame`` of a FrameBoxes where each (frame, drone) is one step."""

    def __init__(self, boxes: FrameBoxes, order: dict):
        self.boxes, self.ids, self.has_ids = boxes, boxes.ids, True
        self.frames = boxes.frames * len(order) + np.array([order[v] for v in boxes.views], dtype=np.int64)

    def __len__(self) -> int:
        return len(self.frames)

    def by_frame(self) -> dict:
        return rows_by_frame(self.frames)


def iou_matrix(a, b) -> np.ndarray:
    """(N, M) intersection over union of (N, 4) and (M, 4) boxes ``x_min y_min x_max y_max``."""
    a, b = np.asarray(a, dtype=np.float64).reshape(-1, 4), np.asarray(b, dtype=np.float64).reshape(-1, 4)
    w = np.clip(np.minimum(a[:, None, 2], b[None, :, 2]) - np.maximum(a[:, None, 0], b[None, :, 0]), 0, None)
    h = np.clip(np.minimum(a[:, None, 3], b[None, :, 3]) - np.maximum(a[:, None, 1], b[None, :, 1]), 0, None)
    inter = w * h
    area = lambda x: np.clip(x[:, 2] - x[:, 0], 0, None) * np.clip(x[:, 3] - x[:, 1], 0, None)  # noqa: E731
    union = area(a)[:, None] + area(b)[None, :] - inter
    with np.errstate(invalid='ignore', divide='ignore'):
        return np.where(union > 0, inter / union, 0.0)


def image_metrics(gt: FrameBoxes, pred: FrameBoxes, iou_threshold: float = 0.5) -> TrackingMetrics:
    """CLEAR MOT / IDF1 / precision / recall of ``pred`` against ``gt`` over all their drones (module
    docstring); ``motp_m`` is the mean 1 - IoU of the matches, ``gate`` is 1 - ``iou_threshold``."""
    if not 0 < iou_threshold <= 1:
        raise ValueError(f'iou_threshold must be in (0, 1], got {iou_threshold}')
    order = {v: k for k, v in enumerate(sorted(set(gt.views.tolist()) | set(pred.views.tolist())))}
    gate = 1.0 - iou_threshold

    def costs(g, p):
        c = 1.0 - iou_matrix(gt.boxes[g], pred.boxes[p])
        c[c > gate + 1e-12] = np.nan
        return c

    return tracking_metrics(_Steps(gt, order), _Steps(pred, order), max(gate, 1e-9), costs)


def per_view_metrics(gt: FrameBoxes, pred: FrameBoxes, iou_threshold: float = 0.5) -> dict:
    """drone -> :class:`TrackingMetrics` of that drone's boxes, plus ``'all'`` for all drones together."""
    views = sorted(set(gt.views.tolist()) | set(pred.views.tolist()))
    out = {v: image_metrics(gt.select(gt.views == v), pred.select(pred.views == v), iou_threshold) for v in views}
    out['all'] = image_metrics(gt, pred, iou_threshold)
    return out


def format_view_table(metrics: dict) -> str:
    """One line per drone (and 'all'): boxes, precision, recall, MOTA, IDF1, ID switches, in percent."""
    lines = [f'{"drone":>5} {"gt":>6} {"pred":>6} {"prec%":>7} {"rec%":>7} {"MOTA%":>7} {"IDF1%":>7} {"IDsw":>5}']
    for v, m in metrics.items():
        lines.append(
            f'{v:>5} {m.num_gt:6d} {m.num_pred:6d} {100 * m.precision:7.2f} {100 * m.recall:7.2f} '
            f'{100 * m.mota:7.2f} {100 * m.idf1:7.2f} {m.id_switches:5d}'
        )
    return '\n'.join(lines)


def write_mot_boxes(path, boxes: FrameBoxes) -> None:
    """``frame,id,x,y,w,h,score,drone`` lines (x, y: the top-left pixel-centre coordinate), by frame then drone."""
    order = np.lexsort((boxes.ids, boxes.views, boxes.frames))
    lines = []
    for i in order:
        x0, y0, x1, y1 = boxes.boxes[i]
        lines.append(
            f'{boxes.frames[i]},{boxes.ids[i]},{x0:.2f},{y0:.2f},{x1 - x0:.2f},{y1 - y0:.2f},'
            f'{boxes.scores[i]:.4f},{boxes.views[i]}'
        )
    atomic_write_text(path, ''.join(line + '\n' for line in lines))


def read_mot_boxes(path) -> FrameBoxes:
    """Read what :func:`write_mot_boxes` wrote."""
    rows = [line.split(',') for line in Path(path).read_text().splitlines() if line.strip()]
    if any(len(r) != 8 for r in rows):
        raise ValueError(f'{path}: expected lines frame,id,x,y,w,h,score,drone')
    xywh = np.array([[float(v) for v in r[2:6]] for r in rows]).reshape(-1, 4)
    return FrameBoxes(
        [int(r[0]) for r in rows],
        [r[7] for r in rows],
        [int(r[1]) for r in rows],
        np.column_stack([xywh[:, :2], xywh[:, :2] + xywh[:, 2:]]),
        [float(r[6]) for r in rows],
    )
