#!/usr/bin/env python3
"""Choose the BEV tracker's settings on VALIDATION data only (the detector's protocol): one inference run of a
checkpoint per validation sequence, then the tracker re-run with other settings on the same detections.

Validation sequences (never the test seeds 2xx; ``bash scripts/detector_data.sh val trackval`` makes them):
  data/det_complex_val_s111, data/det_modified_val_s112     the recipe's validation seeds (30 frames)
  data/det_complex_trackval_s113, data/det_modified_trackval_s114   longer ones (60 frames) for identities
  ../shared/matrix_sample frames 0-4 (ground-truth calibration)     real validation frames
Search: coordinate descent from the current defaults (``TrackerSettings``, or those changed by ``--set``), one
parameter at a time over the candidates below, two rounds, keeping a change only if it raises the objective by
``--min_gain`` points: the objective is the mean over the sequences of (IDF1 + MOTA) / 2. Prints every trial,
then the defaults against the best per sequence; writes
``OUT/trials.json`` and ``OUT/tune_tracker.png`` (objective per candidate value of each parameter).

    python scripts/tune_tracker.py [--checkpoint PATH] [--out out/tune_tracker]
    # how the shipped defaults were found: from birth_hits 2 and report_coasting 0, gate_m held (docs/detector.md)
    python scripts/tune_tracker.py --set birth_hits=2 report_coasting=0 --keep gate_m
"""

import argparse
import json
import os
import sys
from dataclasses import asdict, replace
from pathlib import Path

os.environ.setdefault('OMP_NUM_THREADS', '1')

import numpy as np  # noqa: E402
import torch  # noqa: E402

from matrix_core.bev.checkpoint import load_model  # noqa: E402
from matrix_core.bev.data import BevFrames  # noqa: E402
from matrix_core.bev.evaluation import ground_truth_points, track_and_score  # noqa: E402
from matrix_core.bev.inference import run_frames  # noqa: E402
from matrix_core.fusion.settings import shipped_checkpoint  # noqa: E402
from matrix_core.tracking import TrackerSettings  # noqa: E402

SHARED = Path(os.environ.get('MATRIX_SHARED', Path(__file__).resolve().parents[1].parent / 'shared'))
SEQUENCES = {
    'complex val s111': Path('data/det_complex_val_s111'),
    'modified val s112': Path('data/det_modified_val_s112'),
    'complex trackval s113': Path('data/det_complex_trackval_s113'),
    'modified trackval s114': Path('data/det_modified_trackval_s114'),
    'real 0-4 (val)': SHARED / 'matrix_sample',
}
CANDIDATES = {
    'gate_m': [0.75, 1.0, 1.5, 2.0],
    'gate_growth_m': [0.5, 1.0, 1.5],
    'high_score': [0.4, 0.5, 0.6],
    'low_score': [0.1, 0.2, 0.3],
    'birth_hits': [1, 2, 3],
    'max_misses': [2, 3, 5, 8],
    'accel_noise': [1.0, 2.0, 4.0],
    'measurement_noise_m': [0.15, 0.3, 0.5],
    'report_coasting': [0, 1, 2],
    'use_offsets': [True, False],
}


def parse_setting(text: str) -> tuple:
    """'birth_hits=2' -> ('birth_hits', 2), typed like the TrackerSettings field."""
    name, _, value = text.partition('=')
    default = getattr(TrackerSettings(), name, None)
    if default is None or not value:
        sys.exit(f'--set {text}: expected NAME=VALUE with NAME one of {sorted(CANDIDATES)}')
    return name, (value.lower() in ('1', 'true')) if isinstance(default, bool) else type(default)(value)


def scores(runs: dict, settings: TrackerSettings) -> dict:
    """name -> {'IDF1', 'MOTA', 'MT %', 'IDsw', 'MODA'} (percent) of the tracker with ``settings``."""
    out = {}
    for name, (frames, outputs, gt) in runs.items():
        r = track_and_score(frames, outputs, gt, settings)
        t = r.tracking
        out[name] = {
            'IDF1': 100 * t.idf1,
            'MOTA': 100 * t.mota,
            'MT %': 100 * t.mostly_tracked / max(t.num_gt_ids, 1),
            'IDsw': t.id_switches,
            'MODA': 100 * r.detection.moda,
        }
    return out


def objective(per_sequence: dict) -> float:
    return float(np.mean([(s['IDF1'] + s['MOTA']) / 2 for s in per_sequence.values()]))


def plot(trials: list, path: Path) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    names = list(CANDIDATES)
    fig, axes = plt.subplots(2, (len(names) + 1) // 2, figsize=(3 * ((len(names) + 1) // 2), 6), squeeze=False)
    for ax, name in zip(axes.flat, names):
        pts = [(t['settings'][name], t['objective']) for t in trials if t['varied'] == name]
        for value in CANDIDATES[name]:
            ys = [y for v, y in pts if v == value]
            if ys:
                ax.scatter([str(value)] * len(ys), ys, s=15)
        ax.set_title(name, fontsize=9)
    axes.flat[0].set_ylabel('mean (IDF1 + MOTA) / 2, %')
    fig.suptitle('tracker settings on validation sequences (one point per trial)')
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--checkpoint', type=Path, default=shipped_checkpoint())
    p.add_argument('--out', type=Path, default=Path('out/tune_tracker'))
    p.add_argument('--rounds', type=int, default=2)
    p.add_argument(
        '--set',
        nargs='*',
        default=[],
        metavar='NAME=VALUE',
        help='start the search from the defaults with these changed',
    )
    p.add_argument(
        '--min_gain',
        type=float,
        default=0.25,
        help='a change is kept only if it raises the objective by at least this (points): smaller '
        'gains are within the noise of a few hundred validation frames',
    )
    p.add_argument('--keep', nargs='*', default=[], metavar='NAME', help='parameters not searched')
    args = p.parse_args(argv)
    torch.set_num_threads(1)
    model, bev_settings = load_model(args.checkpoint)
    runs = {}
    for name, folder in SEQUENCES.items():
        if not folder.is_dir():
            sys.exit(f'{folder} missing: bash scripts/detector_data.sh val trackval')
        data = BevFrames(folder, bev_settings, calibration='ground_truth', cache_images=False)
        failed = {}
        gt = ground_truth_points(data, failed)
        outputs = [o for o in run_frames(model, data, False, failed) if o.frame not in failed]
        runs[name] = (data.frames, outputs, gt)
        print(f'inference: {name}, {len(outputs)} frames', flush=True)
    best = replace(TrackerSettings(), **dict(parse_setting(a) for a in args.set))
    defaults = scores(runs, best)
    best_value = objective(defaults)
    trials = [{'varied': None, 'settings': asdict(best), 'objective': best_value}]
    print(f'start: objective {best_value:.2f}')
    start = best
    for _ in range(args.rounds):
        for name, values in ((n, v) for n, v in CANDIDATES.items() if n not in args.keep):
            for value in values:
                if value == getattr(best, name):
                    continue
                candidate = replace(best, **{name: value})
                value_of = objective(scores(runs, candidate))
                trials.append({'varied': name, 'settings': asdict(candidate), 'objective': value_of})
                print(f'  {name} = {value}: objective {value_of:.2f}', flush=True)
                if value_of >= best_value + args.min_gain:
                    best, best_value = candidate, value_of
                    print(f'  -> kept {name} = {value}', flush=True)
    tuned = scores(runs, best)
    changed = {k: v for k, v in asdict(best).items() if v != getattr(start, k)}
    print(f'\nbest settings (changed from the start): {changed or "none"}; objective {best_value:.2f}')
    print(
        '| sequence | IDF1 start | IDF1 best | MOTA start | MOTA best | MT % start | MT % best | '
        'IDsw start | IDsw best |'
    )
    print('|---|---|---|---|---|---|---|---|---|')
    for name in runs:
        a, b = defaults[name], tuned[name]
        print(
            f'| {name} | {a["IDF1"]:.1f} | {b["IDF1"]:.1f} | {a["MOTA"]:.1f} | {b["MOTA"]:.1f} | '
            f'{a["MT %"]:.1f} | {b["MT %"]:.1f} | {a["IDsw"]} | {b["IDsw"]} |'
        )
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / 'trials.json').write_text(
        json.dumps(
            {
                'checkpoint': str(args.checkpoint),
                'start': asdict(start),
                'best_changed': changed,
                'at_start': defaults,
                'best': tuned,
                'trials': trials,
            },
            indent=1,
            default=str,
        )
    )
    plot(trials, args.out / 'tune_tracker.png')
    print(f'wrote {args.out}/trials.json, tune_tracker.png')
    return 0


if __name__ == '__main__':
    sys.exit(main())
