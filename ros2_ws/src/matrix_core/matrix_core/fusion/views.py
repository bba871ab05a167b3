"""One view's input to a fused frame, and the image scale it is decoded at.

Convention: ``img_H_ground`` (3, 3) maps world ground metres (x, y on z = 0) to full-resolution image
pixels (OpenCV pixel centres), any overall scale or sign (``bev.lifting.orient_ground_homography`` fixes
the sign). It comes from a registration (``Registration.img_H_ground``) or a calibration
(``Camera.img_H_ground()``): ``fusion.view_inputs`` builds views from either message.
"""

import enum
from dataclasses import dataclass

import numpy as np

from matrix_core.geometry.homography import pixel_scale_homography


class ViewInputError(ValueError):
    """A view's input cannot be used for this frame; the message is the reason shown in diagnostics."""


class FrameStatus(enum.IntEnum):
    """What became of one view in one fused frame (its ``reason`` says more)."""

    USED = 0
    MISSING = 1  # not all of it arrived: no image, no geometry, dropped at the sender; expected under load
    REJECTED = 2  # it arrived but cannot be used: bad input, failed or unusable registration, low confidence
    FUSION_FAILED = 3  # the network failed on the frame: no view is used, no detection invented

    def __str__(self) -> str:
        return self.name.lower()

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


@dataclass
class ViewInput:
    """What arrived for one view of a frame.

    Attributes:
        image: (H, W, 3) BGR uint8, or None when missing/undecodable.
        img_H_ground: (3, 3) ground metres -> pixels, or None.
        reason: why the view cannot be used ('' when both parts are there).
        confidence: registration confidence of the homography (None for a calibration).
        network_image: (3, h, w) float32 network input made from ``image`` when it arrived
            (``ViewInputs.decode_early``), or None: the fuser makes it.
        status: :attr:`FrameStatus.MISSING` or ``REJECTED`` when the view cannot be used (default: ``REJECTED``
            when a ``reason`` is given, else ``USED``).
    """

    image: np.ndarray = None
    img_H_ground: np.ndarray = None
    reason: str = ''
    confidence: float = None
    network_image: np.ndarray = None
    status: FrameStatus = None

    def __post_init__(self):
        if self.status is None:
            self.status = FrameStatus.REJECTED if self.reason else FrameStatus.USED

    @property
    def usable(self) -> bool:
        return (
            self.status == FrameStatus.USED
            and self.image is not None
            and self.img_H_ground is not None
            and not self.reason
        )


def check_image(image) -> np.ndarray:
    """A decoded image must be (H, W, 3) uint8 and not empty."""
    if image is None or image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3 or 0 in image.shape:
        desc = 'None' if image is None else f'{image.dtype} {image.shape}'
        raise ViewInputError(f'expected a non-empty (H, W, 3) uint8 BGR image, got {desc}')
    return image


JPEG_REDUCTIONS = (8, 4, 2, 1)  # the scales libjpeg decodes to directly (cv2.IMREAD_REDUCED_COLOR_*)


def jpeg_reduction(full_size: tuple, input_size: tuple) -> int:
    """Largest r in 8, 4, 2, 1 for which a (w, h) ``full_size`` image decoded at 1/r is still at least the
    network's (w, h) ``input_size``: decoding a 1920x1080 JPEG at 960x540 is about 1.5x faster and makes the
    resize to 480x272 3x faster, and loses nothing the network input keeps (mean difference < 1 grey level)."""
    for r in JPEG_REDUCTIONS:
        if full_size[0] // r >= input_size[0] and full_size[1] // r >= input_size[1]:
            return r
    return 1


def at_reduced_resolution(img_H_ground: np.ndarray, r: int) -> np.ndarray:
    """``img_H_ground`` of the full image -> the same for the image decoded at 1/r (pixel centres:
    u_small = (u_full + 0.5) / r - 0.5)."""
    return pixel_scale_homography(1.0 / r, 1.0 / r) @ img_H_ground  # small_H_full
