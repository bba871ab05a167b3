"""Camera dropout at test time: which views are removed for a drop rate and a seed."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ViewSubset:
    rate: float
    seed: int  # -1 when the rate drops nothing (one subset only)
    kept: tuple
    dropped: tuple


def dropped_count(rate: float, num_views: int) -> int:
    """Views removed at ``rate`` (rounded to the nearest whole view; 0.25 of 8 views = 2)."""
    if not 0 <= rate < 1:
        raise ValueError(f'drop rate must be in [0, 1), got {rate}')
    return int(round(rate * num_views))


def dropout_subsets(views, rate: float, seeds) -> list:
    """One :class:`ViewSubset` per seed with ``dropped_count(rate, len(views))`` views drawn at random
    without replacement (seeded by (seed, rate), so every rate gets its own draws); a rate that drops
    nothing gives a single subset with all views."""
    views = tuple(views)
    n = dropped_count(rate, len(views))
    if n == 0:
        return [ViewSubset(rate, -1, views, ())]
    out = []
    for seed in seeds:
        rng = np.random.default_rng([int(seed), int(round(rate * 1000))])
        drop = set(rng.choice(len(views), size=n, replace=False).tolist())
        out.append(
            ViewSubset(
                rate,
                int(seed),
                tuple(v for i, v in enumerate(views) if i not in drop),
                tuple(v for i, v in enumerate(views) if i in drop),
            )
        )
    return out
