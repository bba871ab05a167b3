"""Temporal fusion: the previous frame's BEV features are concatenated with the current ones.

The BEV grid is fixed in the world, so the previous features need no warping even though the drones
move; people move by < 1 m per 0.5 s step, which the dilated convolutions below cover.
"""

import torch
from torch import nn


class TemporalFusion(nn.Module):
    """(B, C, R, Q) current + optional (B, C, R, Q) previous -> (B, C, R, Q).

    A missing previous frame (first frame, after a reset; per sample via ``previous_valid`` (B,) bool)
    is a 0 flag channel with zeroed features, not features pretending to be data.
    """

    def __init__(self, channels: int):
        super().__init__()
        self.convs = nn.Sequential(
            nn.Conv2d(2 * channels + 1, channels, 3, 1, 1, bias=False),
            nn.BatchNorm2d(channels),
            nn.ReLU(inplace=True),
            nn.Conv2d(channels, channels, 3, 1, 2, dilation=2, bias=False),
            nn.BatchNorm2d(channels),
            nn.ReLU(inplace=True),
        )

    def forward(
        self, current: torch.Tensor, previous: torch.Tensor = None, previous_valid: torch.Tensor = None
    ) -> torch.Tensor:
        b, _, r, q = current.shape
        if previous is None:
            previous = torch.zeros_like(current)
            valid = current.new_zeros(b)
        else:
            valid = current.new_ones(b) if previous_valid is None else previous_valid.to(current.dtype)
            previous = previous * valid[:, None, None, None]
        flag = valid[:, None, None, None].expand(b, 1, r, q)
        return current + self.convs(torch.cat([current, previous, flag], dim=1))
