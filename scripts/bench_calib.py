#!/usr/bin/env python3
"""Benchmark of the per-frame checkerboard calibration (matrix_core.calib) on one CPU core.

Runs every drone of a MATRIX folder through DroneCalibrator (prior of the first frame = the reference
calibration, then the previous result) at full resolution (1920x1080) and at half resolution
(960x540: images resized, intrinsics scaled), and prints per resolution the median and p95 time per
frame plus the accuracy against the stored calibration.

    python scripts/bench_calib.py [--dataset ../shared/matrix_sample] [--scales 1.0 0.5] [--repeat 1]
    python scripts/bench_calib.py --sim-frames 50      # also: the simulated acceptance, 3 variants
    python scripts/bench_calib.py --track_corners false  # any CalibSettings flag (here: search every frame)

With ``--sim-frames N`` it also simulates N frames of each simulator variant (seed 7) into a temporary
folder and reports accuracy against the true poses and time per frame (1920x1080).
"""

import argparse
import os
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.status import CalibStatus
from matrix_core.calib.evaluation import pose_errors
from matrix_core.calib.scene import load_scene
from matrix_core.calib.settings import CalibSettings
from matrix_core.datasets import MatrixDataset
from matrix_core.settings import add_settings_arguments, settings_from_namespace


def scaled(image, scale):
    return image if scale == 1.0 else cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)


def bench(dataset, scale, repeat, settings):
    scene = load_scene()
    S = np.array([[scale, 0, 0.5 * scale - 0.5], [0, scale, 0.5 * scale - 0.5], [0, 0, 1.0]])  # pixel centres
    w, h = scene.image_size
    scene = scene.with_intrinsics(S @ scene.K, scene.dist, (round(w * scale), round(h * scale)))
    times, rot, ctr, statuses, stages, tracked = [], [], [], [], {}, 0
    for _ in range(repeat):
        for view in dataset.views:
            ref = scaled(dataset.reference_image(view), scale)
            cal = DroneCalibrator(scene, settings, dataset.reference_camera(view), ref)
            for index, frame in enumerate(dataset.frames):
                image = scaled(dataset.load_image(view, frame), scale)
                t = time.perf_counter()
                r = cal.process(image, 0.5 * index)
                times.append(time.perf_counter() - t)
                statuses.append(r.status)
                tracked += r.tracked
                for stage, seconds in r.timings_s.items():
                    stages.setdefault(stage, []).append(seconds * 1000)
                if r.status is CalibStatus.OK:
                    e = pose_errors(r.camera, dataset.camera(view, frame))
                    rot.append(e[0])
                    ctr.append(e[1])
    t = np.array(times) * 1000
    size = f'{scene.image_size[0]}x{scene.image_size[1]}'
    line = (
        f'{size}: {len(t)} frames, time per frame median {np.median(t):.0f} ms, '
        f'p95 {np.percentile(t, 95):.0f} ms, max {t.max():.0f} ms; ok {statuses.count(CalibStatus.OK)}, '
        f'stale {statuses.count(CalibStatus.STALE)}, failed {statuses.count(CalibStatus.FAILED)}, tracked {tracked} '
        f'(stage medians: ' + ', '.join(f'{k} {np.median(v):.0f} ms' for k, v in stages.items() if k != 'total') + ')'
    )
    if rot:
        line += (
            f'; ok frames vs stored: rotation median {np.median(rot):.3f} deg (max {max(rot):.3f}), '
            f'centre median {np.median(ctr) * 100:.1f} cm (max {max(ctr) * 100:.1f})'
        )
    print(line, flush=True)


def bench_sim(frames: int, overrides: dict):
    from matrix_core.calib.evaluation import summarize_errors
    from matrix_core.calib.scene import default_config_path
    from matrix_core.cli.calibrate import calibrate_dataset, simulated_sequence
    from matrix_core.datasets import open_dataset

    for variant in ('simple', 'complex', 'modified'):
        with tempfile.TemporaryDirectory() as tmp:
            data = simulated_sequence(variant, frames, 7, Path(tmp) / 'data')
            settings = CalibSettings(config=str(default_config_path(f'sim_{variant}.yaml')), **overrides)
            rows = calibrate_dataset(open_dataset(data), Path(tmp) / 'calib', settings, compare=True)
        s = summarize_errors(rows)
        t = np.array([r['time_s'] for r in rows]) * 1000
        print(
            f"sim {variant}: {s['frames']} images ({frames} frames x 8 drones): ok {s['ok']}, stale {s['stale']}, "
            f"failed {s['failed']}; rotation median {s.get('rot_median_deg', float('nan')):.3f} deg "
            f"(max {s.get('rot_max_deg', float('nan')):.3f}), centre median "
            f"{100 * s.get('centre_median_m', float('nan')):.1f} cm "
            f"(max {100 * s.get('centre_max_m', float('nan')):.1f}); "
            f"time median {np.median(t):.0f} ms, p95 {np.percentile(t, 95):.0f} ms",
            flush=True,
        )


def main():
    root = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        '--dataset', default=os.environ.get('MATRIX_SHARED', str(root.parent / 'shared')) + '/matrix_sample'
    )
    parser.add_argument('--scales', type=float, nargs='*', default=[1.0, 0.5])
    parser.add_argument('--repeat', type=int, default=1)
    parser.add_argument('--sim-frames', type=int, default=0, help='also run the simulated acceptance (0 = off)')
    add_settings_arguments(parser, CalibSettings)
    args = parser.parse_args()
    settings = settings_from_namespace(CalibSettings, args)
    # The simulated variants take their own scene config; every other flag applies to them too.
    overrides = {k: v for k, v in vars(settings).items() if k != 'config' and v != getattr(CalibSettings(), k)}
    cv2.setNumThreads(1)  # one core, as on each drone's computer
    dataset = MatrixDataset(args.dataset)
    print(
        f'bench_calib: {dataset.root}, {len(dataset.views)} drones x {len(dataset.frames)} frames, '
        f'1 OpenCV thread, {settings}'
    )
    for scale in args.scales:
        bench(dataset, scale, args.repeat, settings)
    if args.sim_frames:
        bench_sim(args.sim_frames, overrides)


if __name__ == '__main__':
    main()
