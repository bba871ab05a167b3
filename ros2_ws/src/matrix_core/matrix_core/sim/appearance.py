"""Pedestrian looks: mostly dark, muted clothing (black/grey/charcoal suits, dark blue, brown, some lighter
shirts, some dresses, like the real MATRIX crowd at dusk), skin (also greyish, as under dusk light), hair,
and the per-part shading factors of the lit and the shaded side.

Colours are BGR of a surface facing the light; the renderer multiplies them by :data:`SHADED` on the side
away from the light (a person's lit side is brighter).
"""

import numpy as np

SHADED, LIT = 0.7, 1.05  # brightness of the side away from / facing the light (times the colour)

_SUITS = np.array(
    [
        [28, 28, 30],
        [45, 45, 48],
        [62, 62, 64],
        [75, 73, 70],
        [95, 95, 98],
        [58, 48, 40],
        [80, 55, 38],
        [40, 50, 65],
        [52, 58, 70],
        [72, 66, 60],
        [105, 102, 100],
    ],
    dtype=float,
)  # BGR: black, greys, charcoal, dark blue, brown
_LIGHT_SHIRTS = np.array(
    [[170, 170, 172], [200, 200, 205], [150, 160, 170], [120, 130, 150], [110, 110, 112], [140, 120, 100]], dtype=float
)
_DRESSES = np.array(
    [[30, 30, 35], [40, 30, 80], [70, 40, 40], [90, 90, 95], [50, 60, 110], [100, 80, 120]], dtype=float
)
_SKIN = np.array(
    [[140, 170, 215], [120, 150, 200], [95, 120, 165], [70, 90, 125], [50, 65, 90], [125, 135, 150], [100, 108, 118]],
    dtype=float,
)  # the last two: greyish (dusk)
_HAIR = np.array([[15, 15, 18], [25, 30, 40], [30, 45, 70], [60, 80, 110], [110, 110, 115]], dtype=float)
DRESS_FRACTION = 0.2
LIGHT_SHIRT_FRACTION = 0.15


def person_looks(rng: np.random.Generator, n: int, dress_fraction: float = DRESS_FRACTION) -> tuple:
    """Colours and dress flags of ``n`` people.

    Returns:
        colors: (n, 4, 3) uint8 BGR of shirt (or dress), trousers (or legs), skin, hair; dress: (n,) bool.
    """
    suit = _SUITS[rng.integers(0, len(_SUITS), n)] * rng.uniform(0.8, 1.2, (n, 1))
    light = rng.random(n) < LIGHT_SHIRT_FRACTION
    shirt = np.where(light[:, None], _LIGHT_SHIRTS[rng.integers(0, len(_LIGHT_SHIRTS), n)], suit)
    shirt = shirt + rng.normal(0, 5, (n, 3))
    trousers = suit + rng.normal(0, 4, (n, 3))
    dress = rng.random(n) < dress_fraction
    dress_color = _DRESSES[rng.integers(0, len(_DRESSES), n)] + rng.normal(0, 6, (n, 3))
    skin = _SKIN[rng.integers(0, len(_SKIN), n)] + rng.normal(0, 4, (n, 3))
    shirt = np.where(dress[:, None], dress_color, shirt)
    legs = np.where(dress[:, None], np.where(rng.random((n, 1)) < 0.5, skin, suit * 0.6), trousers)
    hair = _HAIR[rng.integers(0, len(_HAIR), n)]
    colors = np.clip(np.stack([shirt, legs, skin, hair], axis=1), 0, 255).astype(np.uint8)
    return colors, dress
