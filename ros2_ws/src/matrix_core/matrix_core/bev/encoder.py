"""Small CNN shared by all views, trained from scratch (no pretrained weights are available offline)."""

import torch
from torch import nn


def conv_bn(cin: int, cout: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(cin, cout, 3, stride, 1, bias=False), nn.BatchNorm2d(cout), nn.ReLU(inplace=True))


class ResidualBlock(nn.Module):
    """Two 3x3 convolutions with an identity shortcut (ResNet basic block, no downsampling)."""

    def __init__(self, channels: int):
        super().__init__()
        self.body = nn.Sequential(
            conv_bn(channels, channels), nn.Conv2d(channels, channels, 3, 1, 1, bias=False), nn.BatchNorm2d(channels)
        )

    def forward(self, x):
        return torch.relu(x + self.body(x))


class SmallEncoder(nn.Module):
    """Trimmed ResNet-style encoder with features at stride 4.

    Shapes: (N, 3, H, W) normalised RGB -> (N, out_channels, H / 4, W / 4); H and W multiples of 8.
    A stride-8 branch adds context and is upsampled back to stride 4.
    """

    stride = 4

    def __init__(self, out_channels: int = 32, width: int = 32):
        super().__init__()
        self.stem = nn.Sequential(conv_bn(3, width // 2, 2), conv_bn(width // 2, width, 2), ResidualBlock(width))
        self.down = nn.Sequential(conv_bn(width, 2 * width, 2), ResidualBlock(2 * width))
        self.fuse = nn.Sequential(nn.Conv2d(3 * width, out_channels, 1), nn.ReLU(inplace=True))
        self.out_channels = out_channels

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        s4 = self.stem(x)
        s8 = self.down(s4)
        up = nn.functional.interpolate(s8, size=s4.shape[-2:], mode='bilinear', align_corners=False)
        return self.fuse(torch.cat([s4, up], dim=1))
