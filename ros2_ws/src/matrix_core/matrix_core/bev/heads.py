"""Output heads on the fused BEV features.

Convention (per BEV cell): ``heatmap`` logit of a person centre in the cell; ``offset`` (2) = person
position minus cell centre, metres (x, y); ``tracking`` (2) = the same person's position in the previous
frame minus its current position, metres (CenterTrack's tracking offset, world frame).
"""

import torch
from torch import nn


def head(cin: int, cout: int, hidden: int, bias: float = 0.0) -> nn.Sequential:
    last = nn.Conv2d(hidden, cout, 1)
    nn.init.constant_(last.bias, bias)
    return nn.Sequential(nn.Conv2d(cin, hidden, 3, 1, 1), nn.ReLU(inplace=True), last)


class BevHeads(nn.Module):
    """(B, C, R, Q) -> dict heatmap (B, 1, R, Q) logits, offset (B, 2, R, Q), tracking (B, 2, R, Q)."""

    def __init__(self, channels: int, hidden: int = 32):
        super().__init__()
        # bias -2.19 = logit(0.1): CenterNet's prior so the focal loss starts stable
        self.heatmap = head(channels, 1, hidden, bias=-2.19)
        self.offset = head(channels, 2, hidden)
        self.tracking = head(channels, 2, hidden)

    def forward(self, x: torch.Tensor) -> dict:
        return {'heatmap': self.heatmap(x), 'offset': self.offset(x), 'tracking': self.tracking(x)}
