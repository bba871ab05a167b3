"""Training augmentation of one view's network-input image, with the homography kept in step.

Every function takes a (h, w, 3) uint8 RGB image at the network input size (what ``BevFrames`` caches) and a
``numpy.random.Generator``. Photometric changes, blur, noise and JPEG leave the geometry alone; the
scale-and-crop moves pixels by a 3x3 affine ``aug_H_input`` (input pixels -> augmented pixels, pixel-centre
convention as everywhere, see ``geometry/homography.py``), which :func:`augment_feat_H_grid` folds into the
view's ``feat_H_grid`` so that a ground point still lifts from the pixel it now appears at. The sim-to-real
gap is what these target: camera colour/exposure, lens softness, sensor noise, compression and
drone altitude/framing differ between the simulator and the real MATRIX frames.
"""

from dataclasses import dataclass, field

import cv2
import numpy as np

from matrix_core.geometry.homography import pixel_scale_homography


@dataclass
class AugmentConfig:
    """Section ``augment:`` of the training YAML. Probabilities are per view and sample; a range [a, b] is
    sampled uniformly (zoom log-uniformly). Off by default: the shipped configs reproduce as trained."""

    enabled: bool = False
    p_photometric: float = 0.8
    brightness: float = 0.3  # multiplicative factor in [1 - b, 1 + b]
    contrast: float = 0.3  # around the image's mean grey, factor in [1 - c, 1 + c]
    saturation: float = 0.4  # factor in [1 - s, 1 + s]
    hue_deg: float = 10.0  # hue shift in [-hue, +hue] degrees
    gamma: float = 0.3  # exponent in [1 / (1 + g), 1 + g] (log-uniform)
    channel_gain: float = 0.1  # each of R, G, B scaled by [1 - g, 1 + g] (white balance)
    p_greyscale: float = 0.05
    p_blur: float = 0.3
    blur_sigma: list = field(default_factory=lambda: [0.3, 1.5])  # input pixels
    p_noise: float = 0.3
    noise_std: list = field(default_factory=lambda: [1.0, 8.0])  # grey levels (0..255)
    p_jpeg: float = 0.3
    jpeg_quality: list = field(default_factory=lambda: [30, 90])
    p_scale_crop: float = 0.5
    zoom: list = field(default_factory=lambda: [0.8, 1.25])  # > 1 magnifies
    shift: float = 0.1  # translation up to this fraction of the image width/height

    def __post_init__(self):
        probs = {k: v for k, v in vars(self).items() if k.startswith('p_')}
        bad = {k: v for k, v in probs.items() if not 0 <= v <= 1}
        if bad:
            raise ValueError(f'augment: probabilities must be in [0, 1], got {bad}')
        for name in ('blur_sigma', 'noise_std', 'jpeg_quality', 'zoom'):
            lo_hi = getattr(self, name)
            if len(lo_hi) != 2 or not 0 <= lo_hi[0] <= lo_hi[1]:
                raise ValueError(f'augment: {name} must be [low, high] with 0 <= low <= high, got {lo_hi}')
        if self.zoom[0] <= 0 or not 1 <= self.jpeg_quality[0] <= self.jpeg_quality[1] <= 100:
            raise ValueError('augment: zoom must be positive and jpeg_quality within [1, 100]')
        for name in ('brightness', 'contrast', 'saturation', 'channel_gain'):
            if not 0 <= getattr(self, name) < 1:
                raise ValueError(f'augment: {name} must be in [0, 1), got {getattr(self, name)}')
        if self.hue_deg < 0 or self.gamma < 0 or not 0 <= self.shift < 1:
            raise ValueError('augment: hue_deg and gamma must be >= 0 and shift in [0, 1)')


def _around_one(rng: np.random.Generator, amount: float) -> float:
    return float(rng.uniform(1.0 - amount, 1.0 + amount))


def photometric(rgb: np.ndarray, config: AugmentConfig, rng: np.random.Generator) -> np.ndarray:
    """(h, w, 3) uint8 RGB -> same: gamma, white balance, brightness, contrast, saturation, hue, greyscale.

    Pointwise per channel, so it runs as look-up tables (float passes over the image cost about 6x more).
    """
    g = np.exp(rng.uniform(-1.0, 1.0) * np.log1p(config.gamma))
    gains = np.array([_around_one(rng, config.channel_gain) for _ in range(3)]) * _around_one(rng, config.brightness)
    levels = np.arange(256.0)[:, None] / 255.0
    curve = levels**g * gains  # (256, 3)
    # contrast pivots on the mean grey, taken through the curve at the mean of each channel (cheap, close)
    mean = float(np.mean(curve[np.round(cv2.mean(rgb)[:3]).astype(int), range(3)]))
    curve = (curve - mean) * _around_one(rng, config.contrast) + mean
    out = cv2.LUT(rgb, _to_lut(curve * 255.0))
    hsv = cv2.cvtColor(out, cv2.COLOR_RGB2HSV)  # uint8: H in [0, 180), S and V in [0, 255]
    shift = rng.uniform(-config.hue_deg, config.hue_deg) / 2.0
    hue = (np.arange(256) + int(round(shift))) % 180
    sat = np.arange(256) * _around_one(rng, config.saturation)
    out = cv2.cvtColor(cv2.LUT(hsv, _to_lut(np.stack([hue, sat, np.arange(256)], axis=1))), cv2.COLOR_HSV2RGB)
    if rng.random() < config.p_greyscale:
        out = cv2.cvtColor(cv2.cvtColor(out, cv2.COLOR_RGB2GRAY), cv2.COLOR_GRAY2RGB)
    return out


def _to_lut(values: np.ndarray) -> np.ndarray:
    """(256, 3) grey levels -> (1, 256, 3) uint8 table for ``cv2.LUT`` (rounded, clipped)."""
    return np.clip(np.round(values), 0, 255).astype(np.uint8).reshape(1, 256, 3)


def gaussian_blur(rgb: np.ndarray, sigma: float) -> np.ndarray:
    """(h, w, 3) uint8 -> same, blurred with a Gaussian of ``sigma`` pixels."""
    return cv2.GaussianBlur(rgb, (0, 0), sigmaX=float(sigma), borderType=cv2.BORDER_REFLECT_101)


def gaussian_noise(rgb: np.ndarray, std: float, rng: np.random.Generator) -> np.ndarray:
    """(h, w, 3) uint8 -> same plus i.i.d. Gaussian noise of ``std`` grey levels.

    OpenCV's generator is 3x faster than numpy's here; seeding it from ``rng`` right before the draw keeps
    the result a function of ``rng`` alone (OpenCV's generator is per thread).
    """
    cv2.setRNGSeed(int(rng.integers(2**31)))
    noise = np.empty(rgb.shape, np.float32)
    cv2.randn(noise, 0.0, (float(std),) * 3)
    return cv2.add(rgb, noise, dtype=cv2.CV_8U)  # rounds and saturates


def jpeg_round_trip(rgb: np.ndarray, quality: int) -> np.ndarray:
    """(h, w, 3) uint8 RGB -> same after JPEG encoding at ``quality`` (1..100) and decoding."""
    ok, buf = cv2.imencode('.jpg', cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError('JPEG encoding failed')
    return cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


def scale_crop_affine(size: tuple, zoom: float, shift_px: tuple) -> np.ndarray:
    """(3, 3) ``aug_H_input``: zoom by ``zoom`` about the image centre, then translate by ``shift_px``.

    Args:
        size: (w, h) of the image (output has the same size).
        zoom: magnification (> 1 crops in, < 1 shows more, with padding).
        shift_px: (dx, dy) pixels.
    """
    w, h = size
    cx, cy = (w - 1) / 2.0, (h - 1) / 2.0  # the centre in the pixel-centre convention
    return np.array(
        [[zoom, 0.0, cx + shift_px[0] - zoom * cx], [0.0, zoom, cy + shift_px[1] - zoom * cy], [0.0, 0.0, 1.0]]
    )


def warp_affine(rgb: np.ndarray, aug_H_input: np.ndarray, pad: tuple) -> np.ndarray:
    """(h, w, 3) uint8 -> same size warped by the affine ``aug_H_input``; uncovered pixels get ``pad``
    (RGB 0..255). OpenCV's integer pixel coordinates are pixel centres, as ours."""
    h, w = rgb.shape[:2]
    return cv2.warpAffine(
        rgb,
        aug_H_input[:2],
        (w, h),
        flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=tuple(float(c) for c in pad),
    )


def random_scale_crop(rgb: np.ndarray, config: AugmentConfig, rng: np.random.Generator, pad: tuple) -> tuple:
    """Random zoom (log-uniform in ``config.zoom``) and shift (up to ``config.shift`` of the size).

    Returns:
        (image (h, w, 3) uint8, aug_H_input (3, 3) float64).
    """
    h, w = rgb.shape[:2]
    zoom = float(np.exp(rng.uniform(np.log(config.zoom[0]), np.log(config.zoom[1]))))
    shift = rng.uniform(-config.shift, config.shift, size=2) * (w, h)
    A = scale_crop_affine((w, h), zoom, shift)
    return warp_affine(rgb, A, pad), A


def augment_view(rgb: np.ndarray, config: AugmentConfig, rng: np.random.Generator, pad: tuple) -> tuple:
    """All augmentations of one view, each with its probability: scale-and-crop first (the geometry of the
    scene), then photometric, blur, noise and JPEG (in the order a camera applies them).

    Args:
        rgb: (h, w, 3) uint8 RGB at the network input size.
        pad: RGB colour (0..255) of pixels the crop leaves uncovered.

    Returns:
        (image (h, w, 3) uint8, aug_H_input (3, 3) float64, identity when the geometry was not touched).
    """
    A = np.eye(3)
    if rng.random() < config.p_scale_crop:
        rgb, A = random_scale_crop(rgb, config, rng, pad)
    if rng.random() < config.p_photometric:
        rgb = photometric(rgb, config, rng)
    if rng.random() < config.p_blur:
        rgb = gaussian_blur(rgb, rng.uniform(*config.blur_sigma))
    if rng.random() < config.p_noise:
        rgb = gaussian_noise(rgb, rng.uniform(*config.noise_std), rng)
    if rng.random() < config.p_jpeg:
        rgb = jpeg_round_trip(rgb, rng.integers(config.jpeg_quality[0], config.jpeg_quality[1] + 1))
    return rgb, A


def augment_feat_H_grid(feat_H_grid: np.ndarray, aug_H_input: np.ndarray, stride: int) -> np.ndarray:
    """(3, 3) ``feat_H_grid`` of the augmented image: ``feat_H_input @ aug_H_input @ input_H_feat @ feat_H_grid``.

    Composed after :func:`~matrix_core.bev.lifting.feat_H_grid` (not by changing ``img_H_ground``) so that
    its depth-sign orientation, taken at the original image centre, stays valid: an affine keeps the
    homogeneous depth of every ground point.
    """
    input_H_feat = pixel_scale_homography(stride, stride)
    return np.linalg.inv(input_H_feat) @ aug_H_input @ input_H_feat @ feat_H_grid
