#!/usr/bin/env python3
"""Compare the simulator's crowd motion with the real MATRIX crowd: per-step distance (m per frame at 2 fps),
turn angle between consecutive steps (deg, steps over 0.2 m) and nearest-neighbour distance (m), as percentiles.

Real: the 500 frames of trajectories in ``../shared/matrix_sample/matchings/Pedestrians`` (the people present in
every frame). Simulated: the crowd model of each variant (``sim/crowd.py``, no rendering), 80 frames after a
5 s warm-up, per seed. ``sim/crowd.py``'s contact distance was chosen with this command.

    python scripts/crowd_stats.py [--variants complex modified] [--seeds 1 2 3]
"""

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from matrix_core.datasets.matrix_reader import MatrixDataset
from matrix_core.sim.config import load_scene_config
from matrix_core.sim.crowd import Crowd

SHARED = Path(os.environ.get('MATRIX_SHARED', Path(__file__).resolve().parents[1].parent / 'shared'))


def crowd_statistics(track: np.ndarray) -> dict:
    """Percentiles of a (F, N, 2) track at 0.5 s per frame: 'step' (m), 'turn' (deg), 'nearest' (m)."""
    steps = np.diff(track, axis=0)
    length = np.linalg.norm(steps, axis=2)
    a, b, la, lb = steps[:-1], steps[1:], length[:-1], length[1:]
    moving = (la > 0.2) & (lb > 0.2)
    cosine = (a * b).sum(axis=2)[moving] / (la[moving] * lb[moving])
    gaps = np.linalg.norm(track[:, :, None] - track[:, None], axis=3) + np.eye(track.shape[1]) * 1e6
    return {
        'step': np.percentile(length, [50, 95]),
        'turn': np.percentile(np.degrees(np.arccos(np.clip(cosine, -1, 1))), [50, 90, 99]),
        'nearest': np.percentile(gaps.min(axis=2), [1, 5, 25, 50]),
    }


def real_track(root: Path) -> np.ndarray:
    """(F, N, 2) positions of the people present in every trajectory frame of a MATRIX folder."""
    ds = MatrixDataset(root)
    positions = [ds.pedestrian_positions(f) for f in ds.trajectory_frames]
    ids = sorted(set.intersection(*[set(p) for p in positions]))
    return np.array([[p[i][:2] for i in ids] for p in positions])


def simulated_track(variant: str, seed: int, frames: int = 80, warm_up: int = 10) -> np.ndarray:
    crowd = Crowd(load_scene_config(variant), np.random.default_rng(seed))
    track = []
    for k in range(warm_up + frames):
        crowd.step(0.5)
        if k >= warm_up:
            track.append(crowd.positions.copy())
    return np.array(track)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--variants', nargs='*', default=['complex', 'modified'])
    p.add_argument('--seeds', nargs='*', type=int, default=[1, 2, 3])
    args = p.parse_args(argv)
    rows = [('real sample', crowd_statistics(real_track(SHARED / 'matrix_sample')))]
    rows += [(f'{v} seed {s}', crowd_statistics(simulated_track(v, s))) for v in args.variants for s in args.seeds]
    print('| crowd | step p50 / p95 (m) | turn p50 / p90 / p99 (deg) | nearest p1 / p5 / p25 / p50 (m) |')
    print('|---|---|---|---|')
    for name, st in rows:
        print(
            f'| {name} | '
            + ' | '.join(
                ' / '.join(f'{v:.{0 if k == "turn" else 2}f}' for v in st[k]) for k in ('step', 'turn', 'nearest')
            )
            + ' |'
        )
    return 0


if __name__ == '__main__':
    sys.exit(main())
