"""Per-sequence lighting of the simulated scene: sun direction and intensity, ambient level, shadow darkness,
sky colour and a global tint, from clear day to dusk.

The renderer holds one :class:`Lighting` (``Renderer.light``); everything that shades a surface reads it from
there: :meth:`Lighting.color` for flat-coloured surfaces (boxes, people), :meth:`Lighting.gain` for textures
(ground, facades), :attr:`Lighting.shadow_factor` for sun shadows, :attr:`Lighting.direction` for their
direction. :data:`DAY` is the fixed light of the plain scene (``lighting: {enabled: false}``).

Model: a surface with unit normal n receives ``ambient + sun * max(0, n . direction)``; textures and flat colours
are albedos as they look on the ground under :data:`DAY`, so colours scale by the ratio to the lit ground.
Convention: internal world frame (z up); ``direction`` points from the scene towards the sun.
"""

from dataclasses import dataclass

import numpy as np

UP = np.array([0.0, 0.0, 1.0])
DAY_SKY_BGR = (235, 206, 175)
DUSK_SKY_BGR = np.array([105.0, 80.0, 72.0])  # dark blue-grey evening sky (the real frames' facades/sky)
DUSK_TINT_BGR = np.array([0.93, 0.98, 1.04])  # warm evening light


@dataclass(frozen=True)
class Lighting:
    """One sequence's light.

    Attributes:
        direction: (3,) unit vector towards the sun (z > 0).
        sun, ambient: irradiance of the direct sun and of the sky (unitless).
        shadow_factor: brightness of shadowed ground relative to the lit ground (0..1).
        sky: BGR colour of the sky.
        tint: (3,) BGR gains of the light colour and overall level (ones for :data:`DAY`).
        facade_level: extra gain of building facades (darker at dusk).
        plain: the fixed, unshaded look of the plain scene: ground and facade textures are drawn as they are.
    """

    direction: np.ndarray
    sun: float
    ambient: float
    shadow_factor: float
    sky: tuple
    tint: np.ndarray
    facade_level: float = 1.0
    plain: bool = False

    def shade(self, normal) -> float:
        """Irradiance of a surface with unit ``normal`` (3,)."""
        return self.ambient + self.sun * max(0.0, float(np.dot(normal, self.direction)))

    def gain(self, normal) -> np.ndarray:
        """(3,) BGR gain of a texture on a surface with ``normal``, relative to the lit ground."""
        return self.shade(normal) / self.shade(UP) * self.tint

    def color(self, bgr, normal) -> np.ndarray:
        """(3,) float BGR of a flat surface of colour ``bgr`` (its lit albedo under :data:`DAY`) facing
        ``normal``. For :data:`DAY` this is exactly ``bgr * shade(normal)``."""
        if self.plain:
            return np.asarray(bgr, dtype=float) * self.shade(normal)
        return np.asarray(bgr, dtype=float) * DAY.shade(UP) * self.gain(normal)

    @property
    def shadow_mult_256(self) -> int:
        """:attr:`shadow_factor` in 1/256 steps (integer shading of shadowed pixels)."""
        return int(round(self.shadow_factor * 256))


DAY = Lighting(
    direction=np.array([0.45, 0.3, 0.84]) / np.linalg.norm([0.45, 0.3, 0.84]),
    sun=0.45,
    ambient=0.55,
    shadow_factor=0.625,
    sky=DAY_SKY_BGR,
    tint=np.ones(3),
    plain=True,
)


def sample_lighting(cfg, rng) -> Lighting:
    """A random :class:`Lighting` from a :class:`~matrix_core.sim.config.LightingConfig` (``DAY`` when
    ``cfg`` is None or disabled). ``dusk`` in [0, 1] blends clear day into evening: a lower, weaker sun,
    softer shadows, a darker sky, darker facades and warmer light."""
    if cfg is None or not cfg.enabled:
        return DAY
    u = lambda lo_hi: float(rng.uniform(*lo_hi))  # noqa: E731
    dusk = u(cfg.dusk)
    az = np.radians(u(cfg.azimuth_deg))
    el = np.radians(u(cfg.elevation_deg) * (1.0 - 0.5 * dusk))  # the evening sun is low
    direction = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    sun = u(cfg.sun_intensity) * (1.0 - 0.7 * dusk)
    ambient = u(cfg.ambient)
    lo, hi = cfg.shadow_factor
    shadow = float(np.clip(u(cfg.shadow_factor) + dusk * 0.5 * (hi - lo), lo, hi))  # dusk: soft shadows
    sky = np.asarray(DAY_SKY_BGR, dtype=float) * (1.0 - dusk) + DUSK_SKY_BGR * dusk
    warm = rng.normal(0.0, cfg.tint_std)  # light colour varies along the blue-amber axis
    tint = np.array([1.0 - warm, 1.0, 1.0 + warm]) * (1.0 + (DUSK_TINT_BGR - 1.0) * dusk)
    tint *= u(cfg.level) * (1.0 - 0.15 * dusk)
    return Lighting(
        direction=direction,
        sun=sun,
        ambient=ambient,
        shadow_factor=shadow,
        sky=tuple(float(v) for v in np.clip(sky, 0, 255)),
        tint=tint,
        facade_level=1.0 - cfg.dusk_facade_dimming * dusk,
    )
