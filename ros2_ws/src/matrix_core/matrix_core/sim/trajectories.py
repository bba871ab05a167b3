"""Tracker inputs without images: crowd trajectories and seeded noisy detections made from them.

The tracker's benchmark (``scripts/bench_tracker.py``) and tests feed these to ``tracking.BevTracker``:
ground-truth positions (real ``matchings/Pedestrians`` or the simulator's crowd model, no rendering) turned
into what a detector would give, with position noise, misses and false positives.

Convention: internal world metres, frames 0.5 s apart (MATRIX's 2 fps), ids from the trajectories.
"""

from dataclasses import dataclass

import numpy as np

from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.metrics.bev_points import BevPoints
from matrix_core.tracking.track import BevDetections


@dataclass(frozen=True)
class DetectionNoise:
    """How ground truth becomes detections, per frame and person.

    Attributes:
        noise_m: std (m) of the Gaussian position error, per axis.
        miss: probability that a person is not detected in a frame (independent per frame and person).
        false_per_frame: mean of the Poisson number of false positives per frame, uniform in ``area``.
        area: (x_min, y_min, x_max, y_max) metres where false positives fall (the MATRIX square).
        true_scores, false_scores: (low, high) of the uniform confidences of people and of false positives;
            they overlap, so a score alone does not tell a false positive from a person.
        offsets: also give CenterTrack offsets (to the person's previous position, ``offset_noise_m`` std
            per axis; false positives get random ones); False: the tracker has positions only.
    """

    noise_m: float = 0.1
    miss: float = 0.1
    false_per_frame: float = 2.0
    area: tuple = tuple(MATRIX_AREA)
    true_scores: tuple = (0.5, 1.0)
    false_scores: tuple = (0.2, 1.0)
    offsets: bool = False
    offset_noise_m: float = 0.05

    def __post_init__(self):
        if self.noise_m < 0 or self.offset_noise_m < 0 or self.false_per_frame < 0:
            raise ValueError(f'noise_m, offset_noise_m and false_per_frame must be >= 0: {self}')
        if not 0 <= self.miss <= 1:
            raise ValueError(f'miss must be a probability, got {self.miss}')
        for name in ('true_scores', 'false_scores'):
            lo, hi = getattr(self, name)
            if not 0 <= lo <= hi <= 1:
                raise ValueError(f'{name} must be (low, high) within [0, 1], got {getattr(self, name)}')

    def detections(self, gt: BevPoints, seed: int) -> list:
        """[(frame, BevDetections)] for every frame of ``gt`` (needs ids), in frame order; the same ``seed``
        gives the same detections. People come first in a frame, then the false positives."""
        if not gt.has_ids:
            raise ValueError('detections from ground truth need its ids ("frame id x y")')
        rng = np.random.default_rng(seed)
        x0, y0, x1, y1 = self.area
        previous = {}  # person id -> position in the frame before
        out = []
        for f in gt.frame_numbers:
            rows = gt.at(f)
            seen = rng.random(len(rows)) >= self.miss
            xy = gt.xy[rows][seen] + rng.normal(0.0, self.noise_m, (int(seen.sum()), 2))
            scores = rng.uniform(*self.true_scores, len(xy))
            back = np.array([previous.get(int(i), p) - p for i, p in zip(gt.ids[rows][seen], gt.xy[rows][seen])])
            offs = back.reshape(-1, 2) + rng.normal(0.0, self.offset_noise_m, (len(xy), 2))
            previous.update((int(i), p) for i, p in zip(gt.ids[rows], gt.xy[rows]))
            n_false = rng.poisson(self.false_per_frame)
            xy = np.vstack([xy, rng.uniform([x0, y0], [x1, y1], (n_false, 2))])
            scores = np.r_[scores, rng.uniform(*self.false_scores, n_false)]
            offs = np.vstack([offs, rng.normal(0.0, 0.3, (n_false, 2))])
            out.append((int(f), BevDetections(xy, scores, offs if self.offsets else None)))
        return out


def crowd_trajectories(config, seed: int, frames: int, warm_up: int = 10, frame_interval_s: float = 0.5) -> BevPoints:
    """``frame id x y`` of the simulator's crowd (``sim/crowd.py``, social force, no rendering) for
    ``frames`` frames after ``warm_up`` frames (people start at rest); frames numbered from 0.

    Args:
        config: a :class:`~matrix_core.sim.config.SceneConfig` (area, obstacles, crowd).
        seed: the crowd's random stream (start positions, goals, speeds).
    """
    from matrix_core.sim.crowd import Crowd

    if frames < 1 or warm_up < 0:
        raise ValueError(f'need frames >= 1 and warm_up >= 0, got {frames}, {warm_up}')
    crowd = Crowd(config, np.random.default_rng(seed))
    for _ in range(warm_up):
        crowd.step(frame_interval_s)
    f, ids, xy = [], [], []
    for k in range(frames):
        f.append(np.full(len(crowd.ids), k))
        ids.append(crowd.ids)
        xy.append(crowd.positions.copy())
        crowd.step(frame_interval_s)
    return BevPoints(np.concatenate(f), np.concatenate(xy), ids=np.concatenate(ids))


def dataset_trajectories(dataset, first: int = 0, last: int = None) -> BevPoints:
    """``frame id x y`` of a dataset's recorded pedestrians (MATRIX ``matchings/Pedestrians``) over the
    trajectory frames ``first`` .. ``last`` (inclusive; None: to the end)."""
    chosen = [f for f in dataset.trajectory_frames if f >= first and (last is None or f <= last)]
    if not chosen:
        raise ValueError(f'{dataset.root}: no trajectory frames in {first}..{last}')
    f, ids, xy = [], [], []
    for frame in chosen:
        for pid, p in sorted(dataset.pedestrian_positions(frame).items()):
            f.append(frame)
            ids.append(pid)
            xy.append(p[:2])
    return BevPoints(f, np.reshape(xy, (-1, 2)), ids=ids)
