"""Heatmap peaks -> ground-plane detections (max-pool NMS, sub-cell offsets, tracking offsets)."""

import numpy as np
import torch
import torch.nn.functional as F

from matrix_core.geometry.grid import BevGrid
from matrix_core.tracking.track import BevDetections


def decode_detections(heatmap_logits: torch.Tensor, offset: torch.Tensor, tracking: torch.Tensor,
                      grid: BevGrid, score_threshold: float = 0.3, nms_radius_m: float = 0.5,
                      max_detections: int = 200) -> BevDetections:
    """Detections of ONE frame.

    Args:
        heatmap_logits: (1, R, Q) logits.  offset, tracking: (2, R, Q) metres (see ``heads.py``).
        grid: the BEV grid the maps live on.
        score_threshold: minimum sigmoid score of a peak.
        nms_radius_m: a cell is a peak when it is the maximum within this radius (square max-pool window).
        max_detections: keep the highest-scoring peaks.

    Returns:
        :class:`BevDetections` in world metres with scores and tracking offsets. Non-finite network outputs
        raise ValueError rather than producing invented positions.
    """
    scores = torch.sigmoid(heatmap_logits.detach().float())
    if not torch.isfinite(scores).all() or not torch.isfinite(offset).all() or not torch.isfinite(tracking).all():
        raise ValueError('network output contains NaN or infinite values')
    k = 2 * max(int(round(nms_radius_m / grid.cell)), 1) + 1
    peaks = scores.eq(F.max_pool2d(scores[None], k, stride=1, padding=k // 2)[0]) & (scores >= score_threshold)
    _, rows, cols = torch.nonzero(peaks, as_tuple=True)
    s = scores[0, rows, cols]
    order = torch.argsort(s, descending=True)[:max_detections]
    rows, cols, s = rows[order], cols[order], s[order]
    centres = grid.cell_to_world(np.stack([cols.numpy(), rows.numpy()], axis=1).astype(np.float64))
    off = offset.detach().float()[:, rows, cols].T.numpy().astype(np.float64)
    trk = tracking.detach().float()[:, rows, cols].T.numpy().astype(np.float64)
    return BevDetections(centres + off, s.numpy().astype(np.float64), trk)
