"""Per-drone camera effects of the simulator: the render looks like a real camera's image, not a clean pinhole.

A view is rendered at ``supersample`` times the output size through the same camera (intrinsics scaled about
the pixel-centre convention) and averaged down with INTER_AREA, like a sensor integrating over its pixels; then
optical blur, vignetting, exposure and white balance, sensor noise (Gaussian read noise plus shot noise),
gamma/contrast and a JPEG encode/decode round trip (so the frame carries JPEG artefacts even when saved as PNG).
Noise and JPEG quality are those of a 1920 x 1080 camera; a smaller output shows them as the downsampled
full-resolution image would (less noise, finer artefacts: :func:`noise_std_lut`, :func:`effective_jpeg_quality`).

Each drone draws its parameters once per sequence (:class:`DroneEffects`); exposure and white balance jitter a
little per frame. Effects act on pixels only: the camera model, the id buffer and the annotations are those of
the plain render (the id buffer is sampled at the output pixel centres).
"""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.reference_size import REFERENCE_WIDTH


@dataclass(frozen=True)
class DroneEffects:
    """One drone's camera for a sequence. Gains are BGR; ``blur_sigma`` is in pixels of a 640-px-wide image."""

    exposure: float
    white_balance: np.ndarray  # (3,) BGR gains (b, 1, 2 - b)
    gamma: float
    contrast: float
    blur_sigma: float
    noise_sigma: float
    shot_noise: float
    vignetting: float
    jpeg_quality: int


def sample_drone_effects(cfg, rng) -> DroneEffects:
    """Draw one drone's :class:`DroneEffects` uniformly from the ranges of a ``CameraEffectsConfig``."""
    u = lambda lo_hi: float(rng.uniform(*lo_hi))  # noqa: E731
    exposure = u(cfg.exposure)
    blue = u(cfg.white_balance)  # white-balance errors run along the blue-amber axis (no green casts)
    white_balance = np.array([blue, 1.0, 2.0 - blue])
    return DroneEffects(
        exposure=exposure,
        white_balance=white_balance,
        gamma=u(cfg.gamma),
        contrast=u(cfg.contrast),
        blur_sigma=u(cfg.blur_sigma),
        noise_sigma=u(cfg.noise_sigma),
        shot_noise=u(cfg.shot_noise),
        vignetting=u(cfg.vignetting),
        jpeg_quality=int(rng.integers(cfg.jpeg_quality[0], cfg.jpeg_quality[1] + 1)),
    )


def supersampled_camera(camera, factor: float) -> Camera:
    """The same camera at ``factor`` times the image size (rounded): pixel centres map as
    ``u_big = s (u + 0.5) - 0.5`` per axis, the map INTER_AREA down-sampling inverts exactly."""
    W, H = round(camera.width * factor), round(camera.height * factor)
    sx, sy = W / camera.width, H / camera.height
    big_H_img = np.array([[sx, 0.0, (sx - 1) / 2], [0.0, sy, (sy - 1) / 2], [0.0, 0.0, 1.0]])
    return Camera(big_H_img @ camera.K, camera.cam_T_world, W, H, camera.dist)


def downsample(img, ids, width: int, height: int) -> tuple:
    """(image INTER_AREA-averaged to width x height, id buffer sampled at the output pixel centres)."""
    Hb, Wb = ids.shape
    cols = np.clip(np.round((np.arange(width) + 0.5) * Wb / width - 0.5).astype(int), 0, Wb - 1)
    rows = np.clip(np.round((np.arange(height) + 0.5) * Hb / height - 0.5).astype(int), 0, Hb - 1)
    return (cv2.resize(img, (width, height), interpolation=cv2.INTER_AREA), ids[rows[:, None], cols[None, :]])


def jpeg_round_trip(img, quality: int) -> np.ndarray:
    """(H, W, 3) uint8 BGR -> the same image after JPEG encoding at ``quality`` and decoding."""
    ok, buf = cv2.imencode('.jpg', img, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise RuntimeError('JPEG encoding failed')
    return cv2.imdecode(buf, cv2.IMREAD_COLOR)


class CameraEffects:
    """The camera effects of every drone of one sequence.

    Args:
        cfg: ``CameraEffectsConfig`` (None or ``enabled: false``: plain renders, no supersampling).
        n_drones: number of views.
        seed_seq: ``np.random.SeedSequence``; its first child draws the parameters, the next ones each
            drone's per-frame jitter and noise.
    """

    def __init__(self, cfg, n_drones: int, seed_seq):
        params_seq, bank_seq, *noise_seqs = seed_seq.spawn(2 + n_drones)
        rng = np.random.default_rng(params_seq)
        self.enabled = cfg is not None and cfg.enabled
        self.supersample = cfg.supersample if self.enabled else 1.0
        self.jitter = cfg.jitter if self.enabled else 0.0
        self.drones = [sample_drone_effects(cfg, rng) for _ in range(n_drones)] if self.enabled else []
        self._noise_rngs = [np.random.default_rng(s) for s in noise_seqs]
        self._bank_rng = np.random.default_rng(bank_seq)
        self._banks, self._vignette = {}, {}

    def render(self, renderer, camera, people, k: int) -> tuple:
        """Render view ``k`` through drone ``k``'s camera: (image (H, W, 3) uint8, ids (H, W) uint16) at
        ``camera``'s size; the plain ``renderer.render`` when disabled."""
        if not self.enabled:
            return renderer.render(camera, people)
        if self.supersample > 1.0:
            img, ids = renderer.render(supersampled_camera(camera, self.supersample), people)
            img, ids = downsample(img, ids, camera.width, camera.height)
        else:
            img, ids = renderer.render(camera, people)
        return self.apply(img, k), ids

    def apply(self, img, k: int) -> np.ndarray:
        """Drone ``k``'s optics, sensor and encoder on a rendered (H, W, 3) uint8 BGR image (one frame: draws
        its jitter and noise offset from the drone's generator). Order: blur, vignetting, exposure and white
        balance with the tone curve (one per-channel look-up table), noise, JPEG."""
        if not self.enabled:
            return img
        e, rng = self.drones[k], self._noise_rngs[k]
        H, W = img.shape[:2]
        sigma = e.blur_sigma * W / 640.0
        if sigma > 0.05:
            img = cv2.GaussianBlur(img, (0, 0), sigma)
        if e.vignetting > 0:
            img = cv2.multiply(img, self._vignette_map(e.vignetting, W, H), scale=1.0 / 255.0)
        gains = (
            e.exposure
            * (1.0 + self.jitter * rng.standard_normal())
            * e.white_balance
            * (1.0 + self.jitter * rng.standard_normal(3))
        )
        img = cv2.LUT(img, tone_lut(gains, e.gamma, e.contrast))
        # read + shot noise (standard deviation from the signal); unit normals from a per-size bank at a
        # random offset: drawing H*W*3 fresh normals per view would cost as much as rendering it
        bank = self._normal_bank(img.size)
        start = int(rng.integers(0, bank.size - img.size + 1))
        std = cv2.LUT(img, noise_std_lut(e, W))
        noise = cv2.multiply(std, bank[start : start + img.size].reshape(img.shape))
        img = cv2.add(img, noise, dtype=cv2.CV_8U)
        return jpeg_round_trip(img, effective_jpeg_quality(e.jpeg_quality, W))

    def _normal_bank(self, size: int) -> np.ndarray:
        """(2 size,) float32 standard normals, drawn once per image size."""
        if size not in self._banks:
            self._banks[size] = self._bank_rng.standard_normal(2 * size, dtype=np.float32)
        return self._banks[size]

    def _vignette_map(self, strength: float, width: int, height: int) -> np.ndarray:
        """(H, W, 3) uint8 brightness x 255: 255 at the centre, ``255 (1 - strength)`` in the corners."""
        key = (strength, width, height)
        if key not in self._vignette:
            x = (np.arange(width) - (width - 1) / 2) / (width / 2)
            y = (np.arange(height) - (height - 1) / 2) / (width / 2)
            r2 = (x[None, :] ** 2 + y[:, None] ** 2) / (1.0 + (height / width) ** 2)  # 1 in the corners
            v = np.round(255.0 * (1.0 - strength * r2)).astype(np.uint8)
            self._vignette[key] = np.repeat(v[..., None], 3, axis=2)
        return self._vignette[key]


def noise_std_lut(e: DroneEffects, width: int) -> np.ndarray:
    """(256,) float32 noise standard deviation per grey level at an output ``width``: the sensor noise is
    given at REFERENCE_WIDTH and averaging the full-resolution pixels down to ``width`` divides it by
    REFERENCE_WIDTH / width."""
    scale = min(1.0, width / REFERENCE_WIDTH)
    return (scale * np.sqrt(e.noise_sigma**2 + e.shot_noise * np.arange(256))).astype(np.float32)


def effective_jpeg_quality(quality: int, width: int) -> int:
    """JPEG quality at an output ``width`` that leaves artefacts like ``quality`` at 1920 px seen
    downsampled: 8 x 8 blocks would be REFERENCE_WIDTH / width times coarser, so the loss (100 - quality) shrinks."""
    return int(round(100 - (100 - quality) * min(1.0, width / REFERENCE_WIDTH)))


def tone_lut(gains, gamma: float, contrast: float) -> np.ndarray:
    """(256, 1, 3) uint8 per-channel look-up table: BGR ``gains`` (exposure x white balance), then gamma,
    then contrast about mid-grey."""
    x = np.clip(np.arange(256)[:, None] / 255.0 * np.asarray(gains)[None, :], 0.0, 1.0)
    y = 0.5 + (x**gamma - 0.5) * contrast
    return np.clip(np.round(y * 255.0), 0, 255).astype(np.uint8).reshape(256, 1, 3)
