"""Local features and the one interface every feature backend implements.

Convention:
    keypoint coordinates are FULL-resolution image pixels in the internal pixel-centre convention
    (see ``matrix_core.geometry.camera``), whatever resolution the backend works at. A backend that
    resizes by ``s`` maps its coordinates back with ``x_full = (x_s + 0.5) / s - 0.5``.
"""

from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np


@dataclass(frozen=True)
class Features:
    """Keypoints and descriptors of one image.

    Attributes:
        xy: (N, 2) float64 full-resolution pixel-centre coordinates.
        desc: (N, D) float32 descriptors (row i describes xy[i]).
    """

    xy: np.ndarray
    desc: np.ndarray

    def __len__(self) -> int:
        return len(self.xy)

    def subset(self, keep: np.ndarray) -> 'Features':
        """Features selected by a boolean mask or an index array."""
        return Features(self.xy[keep], self.desc[keep])


class FeatureBackend(Protocol):
    """What the registrar needs from a backend (OpenCV SIFT, kornia GFTT-AffNet-*, ...)."""

    name: str

    def extract(self, image: np.ndarray, max_features: int, mask: np.ndarray = None) -> Features:
        """Detect and describe at most ``max_features`` features of a (H, W, 3) BGR or (H, W) uint8 image;
        with ``mask`` ((h, w) bool, any size of the image's aspect) only where it is true."""


def to_gray(image: np.ndarray) -> np.ndarray:
    """(H, W, 3) BGR or (H, W) uint8 -> (H, W) uint8 grey."""
    if image.ndim == 3:
        return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    if image.ndim != 2:
        raise ValueError(f'expected a (H, W) or (H, W, 3) image, got shape {image.shape}')
    return image


def scaled_size(shape: tuple, scale: float) -> tuple:
    """(width, height) of an image of ``shape`` ((H, W, ...)) resized by ``scale``."""
    h, w = shape[:2]
    return max(1, round(w * scale)), max(1, round(h * scale))


def resize(gray: np.ndarray, scale: float, size: tuple = None) -> np.ndarray:
    """Resize by ``scale`` (INTER_AREA when shrinking), or to ``size`` ((width, height)) when given;
    returns the input when scale == 1 and no size is given."""
    if scale == 1.0 and size is None:
        return gray
    size = size or scaled_size(gray.shape, scale)
    return cv2.resize(gray, size, interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR)


def mask_at(mask: np.ndarray, shape: tuple) -> np.ndarray:
    """(h, w) bool ``mask`` resized (nearest) to ``shape`` (rows, columns)."""
    mask = np.asarray(mask, dtype=bool)
    if mask.shape == tuple(shape):
        return mask
    return cv2.resize(mask.astype(np.uint8), (shape[1], shape[0]), interpolation=cv2.INTER_NEAREST).astype(bool)


def to_full_resolution(xy_scaled: np.ndarray, scale: float) -> np.ndarray:
    """(N, 2) pixel-centre coordinates in an image resized by ``scale`` -> full-resolution coordinates."""
    return (np.asarray(xy_scaled, dtype=np.float64) + 0.5) / scale - 0.5
