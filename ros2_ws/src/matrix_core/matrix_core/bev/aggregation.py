"""Fusing the lifted features of any subset of views into one BEV feature map."""

import torch
from torch import nn


def masked_view_pool(bev: torch.Tensor, seen: torch.Tensor, view_mask: torch.Tensor) -> torch.Tensor:
    """Masked mean and max over views.

    Args:
        bev: (B, V, C, R, Q) lifted features per view.
        seen: (B, V, 1, R, Q) 1 where a view's frustum covers the cell.
        view_mask: (B, V) bool, False for views missing in this frame (dropped camera, no calibration).

    Returns:
        (B, 2C + 1, R, Q): mean over contributing views, max over them (0 where none), and the fraction
        of the V views that contribute. A missing view changes only the mask, never adds zeros as data.
    """
    w = seen * view_mask[:, :, None, None, None].to(seen.dtype)  # (B, V, 1, R, Q)
    count = w.sum(dim=1)  # (B, 1, R, Q)
    mean = (bev * w).sum(dim=1) / count.clamp(min=1.0)
    neg = torch.finfo(bev.dtype).min
    mx = torch.where(w > 0, bev, torch.full_like(bev, neg)).amax(dim=1)
    mx = torch.where(count > 0, mx, torch.zeros_like(mx))
    return torch.cat([mean, mx, count / bev.shape[1]], dim=1)


class ViewAggregation(nn.Module):
    """masked_view_pool followed by two 3x3 convolutions: (B, V, C, R, Q) -> (B, out_channels, R, Q)."""

    def __init__(self, in_channels: int, out_channels: int):
        super().__init__()
        self.convs = nn.Sequential(
            nn.Conv2d(2 * in_channels + 1, out_channels, 3, 1, 1, bias=False),
            nn.BatchNorm2d(out_channels),
            nn.ReLU(inplace=True),
            nn.Conv2d(out_channels, out_channels, 3, 1, 1, bias=False),
            nn.BatchNorm2d(out_channels),
            nn.ReLU(inplace=True),
        )

    def forward(self, bev, seen, view_mask):
        return self.convs(masked_view_pool(bev, seen, view_mask))
