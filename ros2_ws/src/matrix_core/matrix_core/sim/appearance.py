"""Pedestrian looks: muted clothing colours (greys, dark blues, browns, like the real MATRIX crowd), skin."""

import numpy as np

_CLOTHES = np.array([[40, 40, 40], [70, 70, 72], [110, 110, 112], [150, 150, 150], [200, 200, 205],
                     [90, 60, 40], [60, 40, 30], [40, 60, 100], [50, 50, 90], [120, 140, 160],
                     [30, 30, 60], [80, 100, 80]], dtype=float)  # BGR
_SKIN = np.array([[140, 170, 215], [110, 140, 190], [80, 105, 150], [60, 80, 115]], dtype=float)


def person_colors(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 3, 3) uint8 BGR of shirt, trousers, skin per person."""
    shirt = _CLOTHES[rng.integers(0, len(_CLOTHES), n)] + rng.normal(0, 8, (n, 3))
    trousers = _CLOTHES[rng.integers(0, 8, n)] * 0.8 + rng.normal(0, 5, (n, 3))
    skin = _SKIN[rng.integers(0, len(_SKIN), n)]
    return np.clip(np.stack([shirt, trousers, skin], axis=1), 0, 255).astype(np.uint8)
