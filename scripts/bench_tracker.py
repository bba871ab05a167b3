#!/usr/bin/env python3
"""Long-run benchmark of the BEV tracker: seeded noisy detections made from ground-truth trajectories (no
images, no network), the tracker run over them, CLEAR MOT (MOTA, ID switches), IDF1 and HOTA (DetA, AssA).

Sequences (40 people unless said; frames 0.5 s apart):
  TUNING (settings may be chosen on these, ``--tune`` searches only these):
    real 0-249        the real MATRIX trajectories (``matrix_sample/matchings/Pedestrians``), frames 0-249
    sim complex 101, sim complex 102      the simulator's crowd (``sim/crowd.py``, complex scene), 500 frames
  HELD-OUT (never used to choose anything; report these):
    real 250-499      the same real people, the later half (the tracker starts fresh at frame 250)
    sim complex 201, sim complex 202      other crowd seeds, 500 frames
    sim modified 203  the modified scene: 50 people, 500 frames
The real trajectories are split in time because all 40 people walk together through all frames (a split by
person would leave every crowd half as dense); the halves do not overlap. Every sequence is run with the
noise seeds of its part (tuning 1 2, held-out 11 12), so held-out noise draws are new as well.

Noise (``sim/trajectories.py`` ``DetectionNoise``): per person and frame a miss with probability ``--miss``,
otherwise the true position plus Gaussian noise of ``--noise-m`` per axis; ``--false-per-frame`` false
positives a frame (Poisson), uniform over the 30 m square; scores uniform in 0.5-1 for people and 0.2-1 for
false positives; no tracking offsets unless ``--offsets``. Prints a row per sequence and noise seed, then the
mean of each part (ID switches also per 500 frames); with ``--tune``, a coordinate-descent search on the
tuning part first (objective: mean (IDF1 + MOTA) / 2, a change kept when it gains ``--min-gain`` points).

    python scripts/bench_tracker.py [--noise-m 0.1 --miss 0.1 --false-per-frame 2] [--set NAME=VALUE ...]
    python scripts/bench_tracker.py --tune          # how the tracker's defaults were chosen (docs/detector.md)
"""

import argparse
import os
import sys
import time
from dataclasses import asdict, fields, replace
from pathlib import Path

import numpy as np

from matrix_core.datasets import open_dataset
from matrix_core.metrics import BevPoints, tracking_metrics
from matrix_core.sim.config import load_scene_config
from matrix_core.sim.trajectories import DetectionNoise, crowd_trajectories, dataset_trajectories
from matrix_core.tracking import BevTracker, TrackerSettings

SHARED = Path(os.environ.get('MATRIX_SHARED', Path(__file__).resolve().parents[1].parent / 'shared'))
TUNING, HELD_OUT = 'tuning', 'held-out'
NOISE_SEEDS = {TUNING: (1, 2), HELD_OUT: (11, 12)}
# name -> (part, what makes its trajectories)
SEQUENCES = {
    'real 0-249': (TUNING, ('real', 0, 249)),
    'sim complex 101': (TUNING, ('sim', 'complex', 101)),
    'sim complex 102': (TUNING, ('sim', 'complex', 102)),
    'real 250-499': (HELD_OUT, ('real', 250, 499)),
    'sim complex 201': (HELD_OUT, ('sim', 'complex', 201)),
    'sim complex 202': (HELD_OUT, ('sim', 'complex', 202)),
    'sim modified 203': (HELD_OUT, ('sim', 'modified', 203)),
}
# values tried by --tune, per setting (the current value is always a candidate)
CANDIDATES = {
    'gate_m': [0.75, 1.0, 1.25, 1.5],
    'gate_growth_m': [0.25, 0.5, 1.0],
    'max_gate_m': [2.0, 3.0, 4.0],
    'birth_hits': [1, 2, 3],
    'max_misses': [3, 6, 10, 20],
    'accel_noise': [1.0, 2.0, 4.0],
    'measurement_noise_m': [0.1, 0.2, 0.3],
    'report_coasting': [0, 1, 2],
}


def trajectories(source: tuple, sim_frames: int) -> BevPoints:
    if source[0] == 'real':
        folder = SHARED / 'matrix_sample'
        if not folder.is_dir():
            sys.exit(f'{folder} missing (bash scripts/data.sh, or set MATRIX_SHARED)')
        return dataset_trajectories(open_dataset(folder), source[1], source[2])
    return crowd_trajectories(load_scene_config(source[1]), seed=source[2], frames=sim_frames)


def run_tracker(settings: TrackerSettings, detections: list) -> BevPoints:
    """Tracks (``frame id x y``) of a fresh tracker over [(frame, BevDetections)]."""
    tracker = BevTracker(settings)
    frames, ids, xy = [], [], []
    for f, dets in detections:
        for t in tracker.update(dets):
            frames.append(f)
            ids.append(t.track_id)
            xy.append(t.xy)
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def hota_function():
    """``matrix_core.metrics.hota.hota_metrics``, or None where this checkout does not have it yet."""
    try:
        from matrix_core.metrics.hota import hota_metrics
    except ImportError:
        return None
    return hota_metrics


def score(gt: BevPoints, tracks: BevPoints, with_hota: bool) -> dict:
    """Percentages (MOTA, IDF1, HOTA, DetA, AssA) and counts (IDsw, FP, FN) of one run."""
    t = tracking_metrics(gt, tracks, gate=1.0)
    row = {'MOTA': 100 * t.mota, 'IDF1': 100 * t.idf1, 'IDsw': t.id_switches, 'FP': t.fp, 'FN': t.fn}
    hota = hota_function() if with_hota else None
    if hota is not None:
        h = hota(gt, tracks, gate=1.0)
        row.update(HOTA=100 * h.hota, DetA=100 * h.det_a, AssA=100 * h.ass_a)
    return row


def evaluate(runs: list, settings: TrackerSettings, with_hota: bool) -> list:
    """One result dict per run (name, part, seed, frames, people, the figures of :func:`score`)."""
    out = []
    for run in runs:
        figures = score(run['gt'], run_tracker(settings, run['detections']), with_hota)
        out.append({k: run[k] for k in ('name', 'part', 'seed', 'frames', 'people')} | figures)
    return out


def objective(results: list) -> float:
    return float(np.mean([(r['IDF1'] + r['MOTA']) / 2 for r in results]))


def per_500(results: list) -> float:
    """ID switches per 500 frames over these runs."""
    return 500.0 * sum(r['IDsw'] for r in results) / sum(r['frames'] for r in results)


def parse_setting(text: str) -> tuple:
    """'birth_hits=2' -> ('birth_hits', 2), typed like the TrackerSettings field."""
    name, _, value = text.partition('=')
    known = {f.name for f in fields(TrackerSettings)}
    if name not in known or not value:
        sys.exit(f'--set {text}: expected NAME=VALUE with NAME one of {sorted(known)}')
    default = getattr(TrackerSettings(), name)
    return name, (value.lower() in ('1', 'true')) if isinstance(default, bool) else type(default)(value)


def tune(runs: list, start: TrackerSettings, min_gain: float, rounds: int) -> TrackerSettings:
    """Coordinate descent over :data:`CANDIDATES` on ``runs`` (tuning ones only), printing every trial."""
    assert all(r['part'] == TUNING for r in runs), 'the search sees tuning sequences only'
    best, best_value = start, objective(evaluate(runs, start, False))
    print(f'search on the tuning part: start objective {best_value:.2f}')
    for _ in range(rounds):
        for name, values in CANDIDATES.items():
            for value in values:
                if value == getattr(best, name):
                    continue
                candidate = replace(best, **{name: value})
                value_of = objective(evaluate(runs, candidate, False))
                print(f'  {name} = {value}: objective {value_of:.2f}', flush=True)
                if value_of >= best_value + min_gain:
                    best, best_value = candidate, value_of
                    print(f'  -> kept {name} = {value}', flush=True)
    changed = {k: v for k, v in asdict(best).items() if v != getattr(start, k)}
    print(f'search: changed {changed or "nothing"}; objective {best_value:.2f}\n')
    return best


def print_table(results: list) -> None:
    cols = [c for c in ('MOTA', 'IDF1', 'HOTA', 'DetA', 'AssA') if c in results[0]]
    print('| sequence | part | noise seed | frames | people | ' + ' | '.join(cols) + ' | IDsw | FP | FN |')
    print('|---|---|---|---|---|' + '---|' * (len(cols) + 3))
    for r in results:
        figures = ' | '.join(f'{r[c]:.1f}' for c in cols)
        print(
            f'| {r["name"]} | {r["part"]} | {r["seed"]} | {r["frames"]} | {r["people"]} | {figures} | '
            f'{r["IDsw"]} | {r["FP"]} | {r["FN"]} |'
        )
    print()
    print('| part | runs | ' + ' | '.join(f'mean {c}' for c in cols) + ' | worst IDF1 | IDsw per 500 frames |')
    print('|---|---|' + '---|' * (len(cols) + 2))
    for part in (TUNING, HELD_OUT):
        rs = [r for r in results if r['part'] == part]
        if rs:
            means = ' | '.join(f'{np.mean([r[c] for r in rs]):.1f}' for c in cols)
            worst = min(r['IDF1'] for r in rs)
            print(f'| {part} | {len(rs)} | {means} | {worst:.1f} | {per_500(rs):.1f} |')


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--noise-m', type=float, default=0.1, help='std (m) of the detection position error per axis')
    p.add_argument('--miss', type=float, default=0.1, help='probability that a person is missed in a frame')
    p.add_argument('--false-per-frame', type=float, default=2.0, help='mean false positives per frame')
    p.add_argument('--offsets', action='store_true', help='give the detections CenterTrack offsets')
    p.add_argument('--sim-frames', type=int, default=500, help='frames of each simulated sequence')
    p.add_argument('--part', choices=(TUNING, HELD_OUT, 'all'), default='all', help='which sequences to run')
    p.add_argument('--set', nargs='*', default=[], metavar='NAME=VALUE', help='tracker settings changed')
    p.add_argument('--tune', action='store_true', help='first search the settings on the tuning part')
    p.add_argument('--min-gain', type=float, default=0.25, help='--tune keeps a change gaining this (points)')
    p.add_argument('--rounds', type=int, default=2, help='--tune: passes over the settings')
    args = p.parse_args(argv)
    noise = DetectionNoise(
        noise_m=args.noise_m, miss=args.miss, false_per_frame=args.false_per_frame, offsets=args.offsets
    )
    settings = replace(TrackerSettings(), **dict(parse_setting(a) for a in args.set))
    t0 = time.perf_counter()
    runs = []
    for name, (part, source) in SEQUENCES.items():
        if args.part not in ('all', part) and not (args.tune and part == TUNING):
            continue
        gt = trajectories(source, args.sim_frames)
        for seed in NOISE_SEEDS[part]:
            runs.append(
                {
                    'name': name,
                    'part': part,
                    'seed': seed,
                    'frames': len(gt.frame_numbers),
                    'people': len(np.unique(gt.ids)),
                    'gt': gt,
                    'detections': noise.detections(gt, seed),
                }
            )
    print(
        f'noise: {noise.noise_m} m, miss {noise.miss}, {noise.false_per_frame} false positives/frame, '
        f'scores people {noise.true_scores} false {noise.false_scores}, offsets {noise.offsets}'
    )
    if args.tune:
        settings = tune([r for r in runs if r['part'] == TUNING], settings, args.min_gain, args.rounds)
        runs = [r for r in runs if args.part in ('all', r['part'])]
    changed = {k: v for k, v in asdict(settings).items() if v != getattr(TrackerSettings(), k)}
    print(f'tracker: TrackerSettings defaults{f", changed {changed}" if changed else ""}')
    with_hota = hota_function() is not None
    if not with_hota:
        print('(matrix_core.metrics.hota is not in this checkout: HOTA, DetA and AssA left out)')
    results = evaluate(runs, settings, with_hota)
    print()
    print_table(results)
    print(f'\n{len(results)} runs in {time.perf_counter() - t0:.0f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
