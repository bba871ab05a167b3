#!/usr/bin/env python3
"""Benchmark of matrix_register: per backend and resolution, time per frame (one CPU thread), matches,
inliers, confidence and the ground-plane homography error against the stored calibrations.

Pairs: every drone's ``reference/`` image vs frames of the real MATRIX sample (default all 8 x 5 = 40 for
SIFT; kornia backends take seconds per image, so they get ``--kornia-pairs`` pairs spread over the drones).
Time per frame = feature extraction of the current image + matching + robust fit + gate (the reference's
features are extracted once and cached, as in the node). Error: mean over visible ground points, full-res px.

    python scripts/bench_register.py                      # all backends at 1920x1080, 960x540, 480x270
    python scripts/bench_register.py --backends sift --scales 0.25 0.5
    python scripts/bench_register.py --simulated          # full-size simulated acceptance (see below)
    python scripts/bench_register.py --backends sift --scales 0.25 --mode track   # registration that tracks

``--simulated``: the acceptance on simulated sequences with the default settings: each variant (simple,
complex, modified) rendered at 1920x1080, 50 frames, seed 3 (kept in ``--sim-dir`` and reused), all 8 drones
x 50 frames registered to their reference/; prints pairs, failures, time and error median / max (criteria:
every pair registered, median <= 0.5 px, worst <= 3 px). About 25 s of rendering and 40 s of registration
per variant on one core. tests/register/test_sim_acceptance.py is its CI-sized version. ``--mode track``
(with ``--reanchor_every``) runs the registration that tracks (each drone's frames in order) and adds
the CPU time per frame (median, p95) and how many frames the flow registered.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

import cv2
from threadpoolctl import threadpool_limits
import numpy as np
from tqdm import tqdm

from matrix_core.datasets import MatrixDataset
from matrix_core.register.acceptance import acceptance_run
from matrix_core.register.backends import BACKENDS
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import RegisterSettings
from matrix_core.register.weights import MissingWeightsError
from matrix_core.settings import parse_bool

# The flags that set RegisterSettings fields of the same names in every run (mode, matching, tracking).
MODE_FLAGS = (
    'mode',
    'reanchor_every',
    'anchor_by_flow',
    'matcher',
    'track_min_inliers',
    'anchor_search_margin_px',
    'track_refine_scale',
)


def feature_budget(backend: str, scale: float, kornia_features: int) -> tuple:
    """(max_features, reference_max_features): the defaults at 480x270; larger images get more features
    (with 4000 at 960x540 or more, the strongest features are the facades' and the ground is lost)."""
    if backend != 'sift':
        return kornia_features, kornia_features
    defaults = RegisterSettings()
    if scale <= 0.25:
        return defaults.max_features, defaults.reference_max_features
    return 16000, 32000


def mode_settings(args) -> dict:
    """The RegisterSettings fields the flags set (mode, matching, tracking), for every run."""
    return {name: getattr(args, name) for name in MODE_FLAGS}


def bench(dataset, backend, scale, pairs, kornia_features, **mode) -> dict:
    """One backend at one scale over ``pairs``; ``mode``: RegisterSettings fields (:func:`mode_settings`)."""
    current, reference = feature_budget(backend, scale, kornia_features)
    settings = RegisterSettings(
        backend=backend, scale=scale, max_features=current, reference_max_features=reference, **mode
    )
    rows, registrars = [], {}
    for view, frame in tqdm(pairs, desc=f'{backend} @ {scale:g}', unit='pair', leave=False):
        if view not in registrars:
            ref_image = dataset.reference_image(view)
            registrars[view] = Registrar(
                settings, ref_image, dataset.reference_camera(view), dataset.area, f'{view}/reference'
            )
        image = dataset.load_image(view, frame)
        start = time.process_time()
        r = registrars[view].register(image, frame)
        cpu = time.process_time() - start
        err = (
            homography_error_px(
                r.ref_H_img,
                dataset.camera(view, frame),
                dataset.reference_camera(view),
                dataset.area,
                settings.exclude_boxes,
            )
            if r.ok
            else float('nan')
        )
        rows.append(
            (
                r.seconds,
                r.matches,
                r.inliers,
                r.confidence,
                err,
                r.ok,
                cpu,
                r.message.startswith('tracked'),
                r.message.startswith('anchor by flow'),
            )
        )
    a = np.array(rows, dtype=float)
    ok = a[:, 5] > 0
    return {
        'backend': backend,
        'size': f'{round(1920 * scale)}x{round(1080 * scale)}',
        'pairs': len(rows),
        'features': current,
        'failed': int((~ok).sum()),
        'ms_median': 1000 * float(np.median(a[:, 0])),
        'ms_max': 1000 * float(np.max(a[:, 0])),
        'cpu_ms_median': 1000 * float(np.median(a[:, 6])),
        'cpu_ms_p95': 1000 * float(np.percentile(a[:, 6], 95)),
        'tracked': int(a[:, 7].sum()),
        'anchors_by_flow': int(a[:, 8].sum()),
        'matches': float(np.median(a[:, 1])),
        'inliers': float(np.median(a[:, 2])),
        'confidence': float(np.median(a[:, 3])),
        'err_median_px': float(np.median(a[ok, 4])) if ok.any() else float('nan'),
        'err_max_px': float(np.max(a[ok, 4])) if ok.any() else float('nan'),
    }


def simulated_acceptance(args) -> int:
    """Full-size simulated acceptance; returns 1 if a criterion is missed."""
    from matrix_core.sim.sequence import simulate
    from matrix_core.sim.settings import SimulateSettings

    missed = 0
    for variant in args.variants:
        folder = Path(args.sim_dir) / f'{variant}_seed{args.sim_seed}_{args.sim_frames}x{args.sim_size[0]}'
        if not (folder / 'matrix_tracker_meta.json').is_file():
            simulate(
                SimulateSettings(
                    config=variant,
                    frames=args.sim_frames,
                    seed=args.sim_seed,
                    out=str(folder),
                    width=args.sim_size[0],
                    height=args.sim_size[1],
                )
            )
        run = acceptance_run(MatrixDataset(folder), RegisterSettings(**mode_settings(args)), progress=True)
        cpu = 1000 * np.array(run['cpu_seconds'])
        ok = run['pairs'] - len(run['failed'])
        met = not run['failed'] and run['error_px_median'] <= 0.5 and run['error_px_max'] <= 3.0
        missed += not met
        print(
            f"{variant:9s} {run['width']}px  registered {ok}/{run['pairs']}  "
            f"time {1000 * run['seconds_median']:4.0f} ms  error median {run['error_px_median']:.2f} px "
            f"max {run['error_px_max']:.2f} px (full-res-equivalent)  "
            f"{'meets' if met else 'MISSES'} the criteria; mode {args.mode}: CPU median {np.median(cpu):.0f} ms, "
            f"p95 {np.percentile(cpu, 95):.0f} ms, by flow {run['tracked']}, anchors by flow {run['anchors_by_flow']}",
            flush=True,
        )
        for pair, reason in run['failed'].items():
            print(f'  failed {pair}: {reason}')
    return int(missed > 0)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    root = Path(__file__).resolve().parent.parent
    default_sample = Path(os.environ.get('MATRIX_SHARED', root.parent / 'shared')) / 'matrix_sample'
    parser.add_argument('--dataset', default=str(default_sample), help='MATRIX folder with reference/')
    parser.add_argument('--backends', nargs='*', default=sorted(BACKENDS), help='backends to run')
    parser.add_argument(
        '--scales', nargs='*', type=float, default=[1.0, 0.5, 0.25], help='image scales (1.0 = 1920x1080)'
    )
    parser.add_argument('--kornia-pairs', type=int, default=2, help='pairs per kornia backend and scale')
    parser.add_argument('--kornia-features', type=int, default=8000, help='features of the kornia detectors')
    parser.add_argument('--json', help='also write the table to this JSON file')
    parser.add_argument('--simulated', action='store_true', help='run the simulated acceptance instead')
    parser.add_argument('--variants', nargs='*', default=['simple', 'complex', 'modified'])
    parser.add_argument('--sim-dir', default='/tmp/matrix_register_sim', help='where the sequences are kept')
    parser.add_argument('--sim-frames', type=int, default=50)
    parser.add_argument('--sim-seed', type=int, default=3)
    parser.add_argument('--sim-size', type=int, nargs=2, default=[1920, 1080], metavar=('W', 'H'))
    parser.add_argument(
        '--mode',
        choices=['reference', 'track'],
        default=RegisterSettings().mode,
        help='registration mode (RegisterSettings.mode)',
    )
    parser.add_argument(
        '--reanchor_every',
        type=int,
        default=RegisterSettings().reanchor_every,
        help='mode track: full registration every this many frames',
    )
    parser.add_argument(
        '--anchor_by_flow',
        type=parse_bool,
        default=RegisterSettings().anchor_by_flow,
        help='mode track: anchors tried by flow to the reference first (true/false)',
    )
    parser.add_argument(
        '--matcher',
        choices=['flann', 'brute'],
        default=RegisterSettings().matcher,
        help='nearest-neighbour search of the feature matching (RegisterSettings.matcher)',
    )
    parser.add_argument(
        '--track_min_inliers',
        type=int,
        default=RegisterSettings().track_min_inliers,
        help='mode track: fewer refined inliers doubt the chain (RegisterSettings.track_min_inliers)',
    )
    parser.add_argument(
        '--anchor_search_margin_px',
        type=float,
        default=RegisterSettings().anchor_search_margin_px,
        help="mode track: a doubted chain's anchor searches the predicted ground grown by this "
        'many pixels, 0 = the whole image (RegisterSettings.anchor_search_margin_px)',
    )
    parser.add_argument(
        '--track_refine_scale',
        type=float,
        default=RegisterSettings().track_refine_scale,
        help='mode track: scale of the refinement against the anchor, 0.25 = the flow\'s own '
        '(RegisterSettings.track_refine_scale)',
    )
    args = parser.parse_args(argv)

    cv2.setNumThreads(1)
    threadpool_limits(1, user_api='blas')  # as the nodes (NodeSettings.apply_threads)
    try:
        import torch

        torch.set_num_threads(1)
    except ImportError:
        pass
    if args.simulated:
        return simulated_acceptance(args)
    dataset = MatrixDataset(args.dataset)
    all_pairs = [(v, f) for v in dataset.views for f in dataset.frames]
    table = []
    for backend in args.backends:
        pairs = all_pairs
        if backend != 'sift':
            step = max(1, len(all_pairs) // max(1, args.kornia_pairs))
            pairs = [all_pairs[(i * step + 2 * i) % len(all_pairs)] for i in range(args.kornia_pairs)]
        for scale in args.scales:
            try:
                table.append(bench(dataset, backend, scale, pairs, args.kornia_features, **mode_settings(args)))
            except MissingWeightsError as exc:
                print(f'{backend}: skipped: {exc}', file=sys.stderr)
                break
            row = table[-1]
            print(
                f"{row['backend']:22s} {row['size']:>9s} feat {row['features']:5d} pairs {row['pairs']:2d} "
                f"failed {row['failed']:2d}  "
                f"time {row['ms_median']:7.0f} ms (max {row['ms_max']:6.0f})  matches {row['matches']:5.0f}  "
                f"inliers {row['inliers']:5.0f}  c {row['confidence']:.2f}  error median {row['err_median_px']:.2f} px "
                f"max {row['err_max_px']:.2f} px  CPU median {row['cpu_ms_median']:.0f} ms p95 {row['cpu_ms_p95']:.0f} "
                f"by flow {row['tracked']}, anchors by flow {row['anchors_by_flow']}",
                flush=True,
            )
    if args.json:
        Path(args.json).write_text(json.dumps(table, indent=1))
    return 0


if __name__ == '__main__':
    t0 = time.perf_counter()
    code = main()
    print(f'bench_register: {time.perf_counter() - t0:.0f} s', file=sys.stderr)
    sys.exit(code)
