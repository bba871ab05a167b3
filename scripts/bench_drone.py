#!/usr/bin/env python3
"""Benchmark of one drone's own work, calibration + registration of each frame, on ONE CPU core.

In deployment each drone has its own computer running its calib and register nodes; at the dataset's
2 Hz that computer keeps up when calib + register take at most 0.5 s per frame on average. This runs
both cores (matrix_core.calib.DroneCalibrator, matrix_core.register.Registrar, default settings, one
OpenCV / torch thread; each frame registered first, and its registration guiding the calibration, as in the
graph) frame after frame for every drone of a MATRIX folder and prints per folder the
CPU time per frame (time.process_time, one thread) of each and of both (median, mean, p95, max) and whether
the mean keeps up; registration ``--mode track`` (optical flow between anchors, see
matrix_core.register.flow_tracking) says how many frames were tracked.

    python scripts/bench_drone.py                                   # real sample + simulated complex 1080p
    python scripts/bench_drone.py --dataset DIR [--dataset DIR2 ..]  # MATRIX folders with reference/
    python scripts/bench_drone.py --sim-frames 0                     # real sample only
    python scripts/bench_drone.py --no-registration-prior            # calib measures the image motion itself
    python scripts/bench_drone.py --track_corners true               # any CalibSettings flag
    python scripts/bench_drone.py --mode track --reanchor_every 10   # registration that tracks
    python scripts/bench_drone.py --mode track --anchor_by_flow false  # its anchors by features only
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import cv2
from threadpoolctl import threadpool_limits
import numpy as np
from tqdm import tqdm

from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.status import CalibStatus
from matrix_core.calib.scene import config_for_dataset, load_scene
from matrix_core.calib.settings import CalibSettings
from matrix_core.cli.calibrate import simulated_sequence
from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.register.registrar import Registrar
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings
from matrix_core.settings import add_settings_arguments, parse_bool, settings_from_namespace

PERIOD_S = 0.5  # the MATRIX frame period (2 Hz)


def _figures(ms: np.ndarray) -> str:
    return f'median {np.median(ms):.0f} ms, mean {ms.mean():.0f}, p95 {np.percentile(ms, 95):.0f}, max {ms.max():.0f}'


def bench(
    root: Path, calib_settings: CalibSettings, registration_prior: bool, register_settings: RegisterSettings
) -> bool:
    """Run every drone of ``root``; prints the figures, returns whether the mean keeps up with 2 Hz."""
    dataset = MatrixDataset(root)
    scene = load_scene(str(config_for_dataset(root)))
    register_settings, _ = settings_for_dataset(register_settings, dataset)
    calib_ms, register_ms, ok, tracked, registered, rot, centre = [], [], 0, 0, 0, [], []
    first = []  # whether each frame is its drone's first (a full registration, calib from its rough prior)
    flow_frames = flow_anchors = 0
    with tqdm(total=len(dataset.views) * len(dataset.frames), desc=root.name, unit='image', leave=False) as bar:
        for view in dataset.views:
            reference = dataset.reference_image(view)
            calibrator = DroneCalibrator(scene, calib_settings, dataset.reference_camera(view), reference)
            registrar = Registrar(
                register_settings, reference, dataset.reference_camera(view), dataset.area, f'{view}/reference'
            )
            for index, frame in enumerate(dataset.frames):
                image = dataset.load_image(view, frame)
                t = time.process_time()
                r = registrar.register(image, frame)
                register_ms.append(1000 * (time.process_time() - t))
                first.append(index == 0)
                flow_frames += r.message.startswith('tracked')
                flow_anchors += r.message.startswith('anchor by flow')
                guide = r if registration_prior else None
                t = time.process_time()
                c = calibrator.process(image, PERIOD_S * index, guide)
                calib_ms.append(1000 * (time.process_time() - t))
                if c.status is CalibStatus.OK:
                    rot.append(rotation_angle_deg(c.camera.R, dataset.camera(view, frame).R))
                    centre.append(float(np.linalg.norm(c.camera.center - dataset.camera(view, frame).center)))
                ok, tracked, registered = ok + (c.status is CalibStatus.OK), tracked + c.tracked, registered + r.ok
                bar.update()
    calib_ms, register_ms, first = np.array(calib_ms), np.array(register_ms), np.array(first)
    both = calib_ms + register_ms
    keeps_up = both.mean() <= 1000 * PERIOD_S
    ref_camera = dataset.reference_camera(dataset.views[0])
    print(
        f'{root}: {len(dataset.views)} drones x {len(dataset.frames)} frames, '
        f'{ref_camera.width}x{ref_camera.height}, CPU time\n'
        f'  calib     {_figures(calib_ms)} (ok {ok}, of them tracked {tracked}, of {len(both)}; vs the stored '
        f'calibration: rotation median {np.median(rot or [np.nan]):.3f} / max {max(rot, default=np.nan):.3f} deg, '
        'centre median '
        f'{100 * np.median(centre or [np.nan]):.1f} / max {100 * max(centre, default=np.nan):.1f} cm)\n'
        f'  register  {_figures(register_ms)} (mode {register_settings.mode}: registered {registered} of '
        f'{len(both)}, of them by flow {flow_frames}, anchors by flow {flow_anchors})\n'
        f'  both      {_figures(both)}: {"keeps" if keeps_up else "does NOT keep"} up with 2 Hz on one core '
        f'(mean <= {1000 * PERIOD_S:.0f} ms); frames over 500 ms: {int((both > 1000 * PERIOD_S).sum())}\n'
        f'  both, mean: each drone\'s first frame {both[first].mean():.0f} ms, the later ones '
        f'{both[~first].mean():.0f} ms',
        flush=True,
    )
    return keeps_up


def main() -> int:
    root = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        '--dataset', action='append', help='MATRIX folder with reference/ (repeatable; default: the real sample)'
    )
    parser.add_argument(
        '--sim-frames',
        type=int,
        default=20,
        help='also simulate this many frames of each of --sim-variants at 1920x1080 (seed 7) and run them (0 = off)',
    )
    parser.add_argument(
        '--sim-variants',
        nargs='+',
        default=['complex'],
        choices=['simple', 'complex', 'modified'],
        help='simulator variants run with --sim-frames',
    )
    parser.add_argument(
        '--registration-prior',
        action=argparse.BooleanOptionalAction,
        default=True,
        help="calib's board prediction from the frame's registration, as the graph runs it (calib "
        'node use_registration:=true); --no-registration-prior: from the image motion',
    )
    defaults = RegisterSettings()
    parser.add_argument(
        '--mode',
        choices=['reference', 'track'],
        default=defaults.mode,
        help='registration mode (RegisterSettings.mode)',
    )
    parser.add_argument(
        '--reanchor_every',
        type=int,
        default=defaults.reanchor_every,
        help='mode track: full registration every this many frames (RegisterSettings.reanchor_every)',
    )
    parser.add_argument(
        '--anchor_by_flow',
        type=parse_bool,
        default=defaults.anchor_by_flow,
        help='mode track: anchors tried by flow to the reference first (RegisterSettings.anchor_by_flow)',
    )
    parser.add_argument(
        '--matcher',
        choices=['flann', 'brute'],
        default=defaults.matcher,
        help='nearest-neighbour search of the feature matching (RegisterSettings.matcher)',
    )
    parser.add_argument(
        '--anchor_search_margin_px',
        type=float,
        default=defaults.anchor_search_margin_px,
        help="mode track: a doubted chain's anchor searches the predicted ground grown by this many "
        'pixels, 0 = the whole image (RegisterSettings.anchor_search_margin_px)',
    )
    parser.add_argument(
        '--track_refine_scale',
        type=float,
        default=defaults.track_refine_scale,
        help="mode track: scale of the refinement against the anchor, 0.25 = the flow's own "
        '(RegisterSettings.track_refine_scale)',
    )
    add_settings_arguments(parser, CalibSettings)  # e.g. --track_corners true; the config follows each folder
    args = parser.parse_args()
    calib_settings = settings_from_namespace(CalibSettings, args)
    register_settings = RegisterSettings(
        mode=args.mode,
        reanchor_every=args.reanchor_every,
        anchor_by_flow=args.anchor_by_flow,
        matcher=args.matcher,
        anchor_search_margin_px=args.anchor_search_margin_px,
        track_refine_scale=args.track_refine_scale,
    )
    cv2.setNumThreads(1)
    threadpool_limits(1, user_api='blas')  # as the nodes (NodeSettings.apply_threads)
    import torch

    torch.set_num_threads(1)
    shared = Path(os.environ.get('MATRIX_SHARED', str(root.parent / 'shared')))
    folders = [Path(d) for d in (args.dataset or [shared / 'matrix_sample'])]
    with tempfile.TemporaryDirectory() as tmp:
        for variant in args.sim_variants if args.sim_frames else []:
            folders.append(simulated_sequence(variant, args.sim_frames, 7, Path(tmp) / f'sim_{variant}'))
        for folder in folders:
            bench(
                folder, calib_settings, args.registration_prior, register_settings
            )  # prints its verdict; a missed target is a figure, not an error of `make bench`
    return 0


if __name__ == '__main__':
    sys.exit(main())
