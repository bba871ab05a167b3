"""Losses of the BEV heads: CenterNet focal loss on the heatmap, L1 on the offsets at person cells."""

import torch
import torch.nn.functional as F


def focal_loss(logits: torch.Tensor, target: torch.Tensor, alpha: float = 2.0, beta: float = 4.0) -> torch.Tensor:
    """Penalty-reduced pixel-wise focal loss (CenterNet, Zhou et al. 2019), normalised by the number of peaks.

    Args:
        logits: (B, 1, R, Q) heatmap logits.
        target: (B, 1, R, Q) Gaussian targets, exactly 1 at the centres.
    """
    pos = target.eq(1).to(logits.dtype)
    log_p = F.logsigmoid(logits)
    log_1p = F.logsigmoid(-logits)
    p = torch.sigmoid(logits)
    pos_loss = -((1 - p) ** alpha) * log_p * pos
    neg_loss = -((1 - target) ** beta) * (p**alpha) * log_1p * (1 - pos)
    return (pos_loss.sum() + neg_loss.sum()) / pos.sum().clamp(min=1.0)


def masked_l1(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean absolute error (metres) over the cells where ``mask`` (B, 1, R, Q) is 1."""
    return (torch.abs(pred - target) * mask).sum() / (mask.sum() * pred.shape[1]).clamp(min=1.0)


def bev_loss(out: dict, targets: dict, weights: dict = None) -> dict:
    """Total and per-term losses; ``weights`` default heatmap 1, offset 1, tracking 1."""
    w = {'heatmap': 1.0, 'offset': 1.0, 'tracking': 1.0, **(weights or {})}
    terms = {
        'heatmap': focal_loss(out['heatmap'], targets['heatmap']),
        'offset': masked_l1(out['offset'], targets['offset'], targets['center_mask']),
        'tracking': masked_l1(out['tracking'], targets['tracking'], targets['tracking_mask']),
    }
    terms['total'] = sum(w[k] * terms[k] for k in ('heatmap', 'offset', 'tracking'))
    return terms
