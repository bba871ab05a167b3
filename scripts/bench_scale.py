#!/usr/bin/env python3
"""Scaling benchmark: the CPU time per frame and the memory of each stage of the pipeline against the number
of drones, the number of people and the size of the area, on simulated sites, calling the core modules directly
(no ROS graph).

Sites: square areas with the drones evenly spaced on a ring around them (1.1 x the half diagonal away, at
0.55 x that height, 70 deg 1280 x 720 cameras rendered at ``--image_scale``, two checkerboards), written as site
files (docs/site-file.md) and rendered with ``simulate --site`` (the ``simple`` crowd, light and effects with
the crowd's count changed; ``--frames`` + 1 frames, the first not timed, and the references, JPEG). Three
sweeps around one base point (``--base``: drones, people, side in metres):

    drones  ``--drones``  (2 4 8 12 16) at the base's people and side
    people  ``--people``  (10 50 100 200) at the base's drones and side
    area    ``--sides``   (15 30 45 60 m a side) at the base's drones and people

Stages, per frame (sums over the drones; where each runs in the graph in brackets):

    decode     each drone's JPEG decoded to grey (drone) and to colour + the network input (fuse,
               ``fusion.view_inputs.ViewInputs``)
    register   ``register.Registrar``, default settings but ``scale`` so that features are found at 480 px wide
               (1920 x 1080 at 0.25 in the graph) (drone)
    calib      ``calib.DroneCalibrator`` guided by the registration, the site's boards (drone)
    network    ``fusion.BevFuser.process`` minus lifting and tracking: encoder per view, aggregation, temporal
               block, heads, peak decoding, and ``prepare_next`` (fuse)
    lifting    ``FrameNetwork._taps_of`` + ``_lift_and_pool``: per view and BEV cell (fuse)
    tracker    ``tracking.BevTracker`` (the fuse node's settings) on the point's crowd as noisy detections
               (``sim.trajectories.DetectionNoise``, people known exactly; ``--tracker_frames`` frames, the
               first 10 not timed) (fuse)
    messages   ``matrix_ros`` conversions: each drone's registration and CameraInfo, fuse's tracks, detections,
               markers, heatmap and their vision_msgs forms (both); skipped where the messages do not import

CPU time is ``time.process_time`` of a worker process per point with one OpenCV, BLAS and torch thread (every
thread of the process, so its own work only: a machine others load distorts it less than wall time). Memory:
the worker's peak RSS (``resource.getrusage`` ru_maxrss: everything, torch's tensors included) and per stage the
peak of Python and numpy allocations (``tracemalloc``, torch's tensors not seen) over one more frame run with
tracemalloc on after the timed ones. The fuse network gets each frame's true camera as its geometry (the
graph's ``input_kind: camera_info``), so its cost does not depend on whether registration succeeds.

Growth: least-squares lines per stage, cost = a + b x: b per drone, per person and per square metre of area.
Linearity in drones: over 4 to 16 drones the largest |cost(N) - fit(N)| / fit(N), the same as the cost per drone
cost(N) / N against fit(N) / N; elasticity: the slope of log cost against log x (1 = proportional, < 1 with a
fixed part, > 1 faster than linear). Acceptance: the total is within 10 % of linear from 4 to 16 drones, and
the tracker takes <= 2 ms per frame at 200 people.

    python scripts/bench_scale.py                        # the default sweeps, ~10 min on 2 cores
    python scripts/bench_scale.py --drones 2 4 --people 10 --sides 15 --frames 1 --out /tmp/scale   # a smoke run

Writes OUT/scale.md (the tables it prints), OUT/scale.png (the curves) and OUT/scale.json; the rendered sites
stay in OUT/sites and are reused.
"""

import argparse
import dataclasses
import json
import math
import os
import resource
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
STAGES = ('decode', 'register', 'calib', 'network', 'lifting', 'tracker', 'messages')
SWEEPS = {'drones': 'drones', 'people': 'people', 'area': 'area_m2'}  # sweep -> the variable it changes
PERIOD_S = 0.5  # frames 0.5 s apart, as the simulator renders them
CAMERA = {'image_size': [1280, 720], 'K': [914.0147, 0.0, 639.5, 0.0, 914.0147, 359.5, 0.0, 0.0, 1.0]}  # 70 deg
REGISTER_WIDTH_PX = 480  # where registration finds features: 1920 x 1080 at its default scale 0.25
TRACKER_WARM_UP = 10  # tracker frames not timed (tracks being born)
LINEAR_TOLERANCE, TRACKER_BUDGET_MS = 0.10, 2.0


# --- the sites ----------------------------------------------------------------------------------------
def point_name(drones: int, people: int, side: float) -> str:
    return f'n{drones}_p{people}_s{side:g}'


def site_document(drones: int, side: float) -> dict:
    """A site file (docs/site-file.md) of a ``side`` x ``side`` m square with ``drones`` drones on a ring."""
    h = side / 2
    ring = 1.1 * math.hypot(h, h)
    altitude = round(0.55 * ring, 3)
    angles = [2 * math.pi * k / drones for k in range(drones)]
    board = 19 * 0.25  # a board's inner corners span 4.75 m
    return {
        'version': 1,
        'name': f'scale_{drones}_{side:g}',
        'area': [-h, -h, h, h],
        'cell_m': 0.25,
        'references': {'source': 'simulate'},
        'drones': [
            {
                'name': f'd{k + 1:02d}',
                'camera': CAMERA,
                'altitude_m': altitude,
                'home': [round(ring * math.cos(a), 3), round(ring * math.sin(a), 3)],
            }
            for k, a in enumerate(angles)
        ],
        'boards': [
            {'name': name, 'origin': [c - board / 2, c - board / 2, 0.0], 'square': 0.25, 'inner_corners': [19, 19]}
            for name, c in (('sw', -h / 2), ('ne', h / 2))
        ],
    }


def render_point(out: Path, drones: int, people: int, side: float, frames: int, image_scale: float, seed: int):
    """The site dataset of one point, rendered once (kept in ``out``)."""
    from matrix_core.sim.settings import SimulateSettings
    from matrix_core.sim.site_sequence import simulate_site
    from matrix_core.site import load_site

    frames += 1  # the first is not timed (measure)
    folder = out / f'{point_name(drones, people, side)}_f{frames}_x{image_scale:g}_seed{seed}'
    if (folder / 'site_dataset.json').is_file():
        return folder
    out.mkdir(parents=True, exist_ok=True)
    site_file, config_file = folder.with_suffix('.site.yaml'), folder.with_suffix('.crowd.yaml')
    site_file.write_text(yaml.safe_dump(site_document(drones, side), sort_keys=False))
    load_site(site_file)  # checked as any site file is
    config = yaml.safe_load((ROOT / 'ros2_ws/src/matrix_core/matrix_core/sim/configs/simple.yaml').read_text())
    config['name'], config['crowd']['count'] = f'scale_{people}', people
    config_file.write_text(yaml.safe_dump(config, sort_keys=False))
    partial = folder.with_name(folder.name + '.partial')
    if partial.exists():
        import shutil

        shutil.rmtree(partial)
    settings = SimulateSettings(
        config=str(config_file),
        frames=frames,
        seed=seed,
        site=str(site_file),
        image_scale=image_scale,
        image_ext='.jpg',
        out=str(partial),
    )
    simulate_site(settings, progress=False)
    partial.rename(folder)
    return folder


# --- the worker: one point's stages --------------------------------------------------------------------
class Clock:
    """CPU seconds per stage (``time.process_time``) and, while ``trace`` is on, the peak tracemalloc bytes."""

    def __init__(self):
        self.cpu = dict.fromkeys(STAGES, 0.0)
        self.peak = dict.fromkeys(STAGES, 0)
        self.trace = False

    def run(self, stage: str, fn, *args):
        if self.trace:
            tracemalloc.reset_peak()
            base = tracemalloc.get_traced_memory()[0]
        t = time.process_time()
        out = fn(*args)
        self.cpu[stage] += time.process_time() - t
        if self.trace:
            self.peak[stage] = max(self.peak[stage], tracemalloc.get_traced_memory()[1] - base)
        return out


def limit_threads() -> None:
    import cv2
    import torch
    from threadpoolctl import threadpool_limits

    cv2.setNumThreads(1)
    threadpool_limits(1, user_api='blas')  # as the nodes (NodeSettings.apply_threads)
    torch.set_num_threads(1)


def message_builders():
    """(per drone (registration, camera) -> messages, per frame (fuser, result) -> messages), or None where
    matrix_ros's messages do not import (no ROS environment)."""
    try:
        from std_msgs.msg import Header

        from matrix_ros import fusion_messages, vision_messages
        from matrix_ros.conversions import camera_to_camera_info, registration_to_msg, seconds_to_stamp
    except ImportError:
        return None

    def drone(stamp, registration, camera):
        header = Header(stamp=seconds_to_stamp(stamp), frame_id='world')
        registration_to_msg(registration, header)
        if camera is not None:
            camera_to_camera_info(camera, header)

    def fuse(stamp, fuser, result):
        header = Header(stamp=seconds_to_stamp(stamp), frame_id='world')
        fusion_messages.tracks_msg(header, result.tracks)
        fusion_messages.detections_msg(header, result.detections, PERIOD_S)
        fusion_messages.markers_msg(header, result.tracks)
        if result.heatmap is not None:
            fusion_messages.heatmap_msg(header, fuser.grid, result.heatmap)
        vision_messages.tracks_3d_msg(header, result.tracks)
        vision_messages.detections_3d_msg(header, result.detections, PERIOD_S)

    return drone, fuse


def instrument_network(fuser, clock: Clock) -> dict:
    """Time the fuser's lifting and tracking inside ``process`` (added to the clock, and kept in the returned
    dict so that the network's share is the rest of ``process``)."""
    inside = {'lifting': 0.0, 'track': 0.0}
    network = fuser.runner.network

    def timed(fn, key):
        def wrapper(*args, **kwargs):
            t = time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                inside[key] += time.process_time() - t

        return wrapper

    network._taps_of = timed(network._taps_of, 'lifting')
    network._lift_and_pool = timed(network._lift_and_pool, 'lifting')
    fuser._track = timed(fuser._track, 'track')
    return inside


def tracker_cost(site, people: int, frames: int, seed: int, tracker_settings) -> tuple:
    """(CPU ms per frame after the warm-up, confirmed tracks in the last frame, tracemalloc peak bytes of one
    update) of a BevTracker on the site's crowd as noisy detections."""
    from matrix_core.sim.config import load_scene_config
    from matrix_core.sim.site_rig import scene_for_site, site_rig
    from matrix_core.sim.trajectories import DetectionNoise, crowd_trajectories
    from matrix_core.tracking import BevTracker

    base = load_scene_config('simple')
    base = dataclasses.replace(base, crowd=dataclasses.replace(base.crowd, count=people))
    config = scene_for_site(site, base, site_rig(site, 1.0, 0.0, base.drones.altitude).homes)
    gt = crowd_trajectories(config, seed=seed, frames=frames + TRACKER_WARM_UP)
    detections = DetectionNoise(area=tuple(site.area)).detections(gt, seed)
    tracker = BevTracker(tracker_settings)
    cpu, out = 0.0, []
    for k, (_, dets) in enumerate(detections):
        t = time.process_time()
        out = tracker.update(dets)
        if k >= TRACKER_WARM_UP:
            cpu += time.process_time() - t
    tracemalloc.start()
    tracker.update(detections[-1][1])
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return 1000 * cpu / frames, len(out), peak


def rss_mb() -> float:
    """Resident memory now (MB)."""
    return int(Path('/proc/self/statm').read_text().split()[1]) * os.sysconf('SC_PAGE_SIZE') / 1e6


def measure(folder: Path, people: int, tracker_frames: int, seed: int) -> dict:
    """One point's figures (the module docstring): CPU ms per frame and memory of each stage."""
    import cv2

    from matrix_core.calib.drone_calibrator import DroneCalibrator
    from matrix_core.calib.prior import initial_prior
    from matrix_core.calib.settings import CalibSettings
    from matrix_core.calib.status import CalibStatus
    from matrix_core.datasets import open_dataset
    from matrix_core.fusion.fuser import BevFuser
    from matrix_core.fusion.settings import FuseSettings
    from matrix_core.fusion.view_inputs import ViewInputs
    from matrix_core.message_fields import camera_info_fields, gray_image_from_msg
    from matrix_core.register.registrar import Registrar
    from matrix_core.register.scene import settings_for_dataset
    from matrix_core.register.settings import RegisterSettings
    from matrix_core.site.calib_scene import site_calib_scene

    limit_threads()
    dataset = open_dataset(folder)
    site, views, frames = dataset.site, list(dataset.views), list(dataset.frames)
    width = dataset.reference_camera(views[0]).width
    register_settings, _ = settings_for_dataset(RegisterSettings(scale=min(1.0, REGISTER_WIDTH_PX / width)), dataset)
    drones = {}
    for v in views:
        scene = site_calib_scene(site, site.drone(v))
        reference = dataset.reference_image(v)
        drones[v] = (
            Registrar(register_settings, reference, dataset.reference_camera(v), dataset.area, f'{v}/reference'),
            DroneCalibrator(scene, CalibSettings(), *initial_prior(scene, v, dataset)),
        )
    fuse_settings = FuseSettings(views=views, area=list(site.area), cell_m=site.cell_m, threads=1, device='cpu')
    fuser = BevFuser(fuse_settings)
    fuser.warm_up()
    inputs = ViewInputs(fuser.input_size, fuse_settings.min_confidence, True)  # the fuse node: jpeg_reduced_decode
    # the messages as they arrive: each JPEG's bytes (read before timing), the frame's true camera
    jpegs = {(v, f): dataset.image_path(v, f).read_bytes() for v in views for f in frames}
    cameras = {(v, f): SimpleNamespace(**camera_info_fields(dataset.camera(v, f))) for v in views for f in frames}
    builders = message_builders()
    clock, inside = Clock(), instrument_network(fuser, Clock())
    rss_setup = rss_mb()
    counts = {'registered': 0, 'calibrated': 0, 'images': 0, 'detections': 0, 'tracks_network': 0}

    def run_frame(index: int, frame: int) -> None:
        stamp = PERIOD_S * index
        geometry, msgs = {}, {}
        for v in views:
            msg = SimpleNamespace(format='jpeg', data=jpegs[v, frame])
            grey = clock.run('decode', gray_image_from_msg, msg)  # the drone's
            clock.run('decode', inputs.decode_early, v, msg)  # fuse's, as the image arrives
            registrar, calibrator = drones[v]
            r = clock.run('register', registrar.register, grey, frame)
            c = clock.run('calib', calibrator.process, grey, stamp, r)
            if builders:
                clock.run('messages', builders[0], stamp, r, c.camera if c.status is CalibStatus.OK else None)
            counts['registered'] += bool(r.ok)
            counts['calibrated'] += c.status is CalibStatus.OK
            counts['images'] += 1
            msgs[v], geometry[v] = msg, cameras[v, frame]
        before = dict(inside)
        t = time.process_time()

        def fuse():
            views_in = {v: inputs.view_input(v, msgs[v], geometry[v], 'camera_info') for v in views}
            result = fuser.process(stamp, views_in)
            fuser.prepare_next()
            return result

        result = fuse()
        spent = time.process_time() - t
        lifting, track = (inside[k] - before[k] for k in ('lifting', 'track'))
        clock.cpu['network'] += spent - lifting - track
        clock.cpu['lifting'] += lifting
        counts['detections'] += len(result.detections)
        counts['tracks_network'] = len(result.tracks)
        if builders:
            clock.run('messages', builders[1], stamp, fuser, result)

    cv2.setRNGSeed(seed)
    run_frame(0, frames[0])  # the first frame: each drone's first full registration and board search, not timed
    first = {k: 1000 * v for k, v in clock.cpu.items()}
    clock.cpu = dict.fromkeys(STAGES, 0.0)
    for index, frame in enumerate(frames[1:], 1):
        run_frame(index, frame)
    per_frame = {k: 1000 * v / (len(frames) - 1) for k, v in clock.cpu.items()}
    rss_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3  # kB on Linux
    # one more frame (the last again, a period later) with tracemalloc on: each stage's peak allocations
    tracemalloc.start()
    clock.trace = True
    tracemalloc.reset_peak()
    base = tracemalloc.get_traced_memory()[0]
    run_frame(len(frames), frames[-1])
    fuse_peak = tracemalloc.get_traced_memory()[1] - base  # whole frame: the fuser's share is the rest
    tracemalloc.stop()
    peaks = dict(clock.peak)
    peaks['network'] = peaks['lifting'] = fuse_peak  # process() is not split for memory: the frame's peak
    tracker_ms, tracks, tracker_peak = tracker_cost(
        site, people, tracker_frames, seed, fuser.settings.tracker_settings()
    )
    per_frame['tracker'] = tracker_ms
    peaks['tracker'] = tracker_peak
    return {
        'cpu_ms': per_frame,
        'tracemalloc_mb': {k: v / 1e6 for k, v in peaks.items()},
        'rss_setup_mb': rss_setup,
        'rss_peak_mb': rss_peak,
        'frames': len(frames) - 1,
        'first_frame_ms': first,
        'image_size': [width, dataset.reference_camera(views[0]).height],
        'grid': list(fuser.grid.shape),
        'messages': builders is not None,
        'tracks': tracks,
        **counts,
    }


def worker(args) -> int:
    spec = json.loads(args.worker)
    figures = measure(Path(spec['folder']), spec['people'], spec['tracker_frames'], spec['seed'])
    print('RESULT ' + json.dumps(figures))
    return 0


# --- fits, table, figure -------------------------------------------------------------------------------
def linear_fit(x, y) -> tuple:
    """(intercept, slope) of the least-squares line y = a + b x."""
    b, a = np.polyfit(np.asarray(x, float), np.asarray(y, float), 1)
    return float(a), float(b)


def max_deviation(x, y) -> float:
    """Largest |y - fit| / fit of the least-squares line through (x, y)."""
    a, b = linear_fit(x, y)
    fit = a + b * np.asarray(x, float)
    return float(np.max(np.abs(np.asarray(y, float) - fit) / np.abs(fit)))


def elasticity(x, y) -> float:
    """Slope of log y against log x (nan where a cost is 0)."""
    y = np.asarray(y, float)
    if np.any(y <= 0):
        return float('nan')
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(y), 1)[0])


def sweep_rows(results: list, sweep: str) -> list:
    key = SWEEPS[sweep]
    return sorted((r for r in results if sweep in r['sweeps']), key=lambda r: r[key])


def total(r: dict) -> float:
    return sum(r['cpu_ms'][s] for s in STAGES)


def growth(results: list) -> dict:
    """Per stage and 'total': per sweep (slope, elasticity); for drones also the deviation from linear over
    4..16 drones (all the sweep's points from 4 up)."""
    out = {}
    for stage in (*STAGES, 'total'):
        row = {}
        for sweep, key in SWEEPS.items():
            rows = sweep_rows(results, sweep)
            if len(rows) < 2:
                continue
            x = [r[key] for r in rows]
            y = [total(r) if stage == 'total' else r['cpu_ms'][stage] for r in rows]
            row[sweep] = {'slope': linear_fit(x, y)[1], 'elasticity': elasticity(x, y)}
            if sweep == 'drones':
                big = [(xi, yi) for xi, yi in zip(x, y) if xi >= 4]
                if len(big) >= 3:
                    row[sweep]['deviation'] = max_deviation(*zip(*big))
        out[stage] = row
    return out


def acceptance(results: list, fits: dict) -> list:
    """(text, held) lines: linearity of the total in drones from 4 to 16, the tracker at 200 people."""
    lines = []
    dev = fits['total'].get('drones', {}).get('deviation')
    drones = [r['drones'] for r in sweep_rows(results, 'drones') if r['drones'] >= 4]
    if dev is None:
        lines.append(
            ('per-drone cost within 10 % of linear from 4 to 16 drones (needs >= 3 drone counts from 4 up)', None)
        )
    else:
        lines.append(
            (
                f'per-drone cost within {LINEAR_TOLERANCE:.0%} of linear over {min(drones)}-{max(drones)} drones: '
                f'largest deviation of the total from its line {dev:.1%}',
                dev <= LINEAR_TOLERANCE,
            )
        )
    crowd = [r for r in results if r['people'] >= 200]
    if not crowd:
        lines.append(('tracker <= 2 ms per frame at 200 people (no point with 200 people)', None))
    else:
        worst = max(r['cpu_ms']['tracker'] for r in crowd)
        lines.append(
            (
                f'tracker <= {TRACKER_BUDGET_MS:g} ms per frame at 200 people: {worst:.2f} ms',
                worst <= TRACKER_BUDGET_MS,
            )
        )
    return lines


def markdown(results: list, fits: dict, lines: list, header: str) -> str:
    out = [header, '']
    out.append(
        '| sweep | drones | people | side m | '
        + ' | '.join(STAGES)
        + ' | total ms | peak RSS MB | registered | calibrated |'
    )
    out.append('|---|---:|---:|---:|' + '---:|' * (len(STAGES) + 4))
    for r in sorted(results, key=lambda r: (r['drones'], r['people'], r['side'])):
        c = r['cpu_ms']
        out.append(
            f'| {", ".join(r["sweeps"])} | {r["drones"]} | {r["people"]} | {r["side"]:g} | '
            + ' | '.join(f'{c[s]:.1f}' for s in STAGES)
            + f' | {total(r):.0f} | {r["rss_peak_mb"]:.0f} | {r["registered"]}/{r["images"]} | '
            f'{r["calibrated"]}/{r["images"]} |'
        )
    out += ['', 'CPU ms per frame (time.process_time, one thread), sums over the drones; growth by least squares:', '']
    out.append(
        '| stage | ms per drone | linear dev. 4-16 drones | elasticity drones | ms per person | elasticity people '
        '| ms per 100 m2 | elasticity area |'
    )
    out.append('|---|---:|---:|---:|---:|---:|---:|---:|')

    def cell(row, sweep, key, scale=1.0, fmt='{:.3f}'):
        v = row.get(sweep, {}).get(key)
        return '-' if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v * scale)

    for stage, row in fits.items():
        out.append(
            f'| {stage} | {cell(row, "drones", "slope")} | {cell(row, "drones", "deviation", 100, "{:.1f} %")} | '
            f'{cell(row, "drones", "elasticity", fmt="{:.2f}")} | {cell(row, "people", "slope", fmt="{:.4f}")} | '
            f'{cell(row, "people", "elasticity", fmt="{:.2f}")} | {cell(row, "area", "slope", 100)} | '
            f'{cell(row, "area", "elasticity", fmt="{:.2f}")} |'
        )
    out.append('')
    for text, held in lines:
        out.append(f'- {text}: ' + ('holds' if held else 'not measured' if held is None else 'DOES NOT HOLD'))
    return '\n'.join(out) + '\n'


def figure(results: list, path: Path) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    labels = {'drones': 'drones', 'people': 'people', 'area': 'area (m$^2$)'}
    fig, axes = plt.subplots(2, 3, figsize=(15, 8), squeeze=False)
    for col, (sweep, key) in enumerate(SWEEPS.items()):
        rows = sweep_rows(results, sweep)
        top, bottom = axes[0][col], axes[1][col]
        if not rows:
            top.set_visible(False)
            bottom.set_visible(False)
            continue
        x = [r[key] for r in rows]
        for stage in STAGES:
            top.plot(x, [max(r['cpu_ms'][stage], 1e-3) for r in rows], 'o-', label=stage)
        top.plot(x, [total(r) for r in rows], 'k--', label='total')
        top.set_yscale('log')
        top.set_xlabel(labels[sweep])
        top.set_ylabel('CPU ms per frame')
        top.grid(True, which='both', alpha=0.3)
        bottom.plot(x, [r['rss_peak_mb'] for r in rows], 'o-', label='peak RSS')
        bottom.plot(x, [r['rss_setup_mb'] for r in rows], 's--', label='RSS after set-up')
        bottom.set_xlabel(labels[sweep])
        bottom.set_ylabel('MB')
        bottom.grid(True, alpha=0.3)
    axes[0][0].legend(fontsize=8)
    axes[1][0].legend(fontsize=8)
    fig.suptitle('matrix-tracker: CPU per frame and memory against drones, people and area (scripts/bench_scale.py)')
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# --- the driver ----------------------------------------------------------------------------------------
def points(args) -> list:
    """[(drones, people, side, sweeps)] of the three sweeps, each point once."""
    n0, p0, s0 = args.base
    n0, p0 = int(n0), int(p0)
    found = {}
    for sweep, values in (('drones', args.drones), ('people', args.people), ('area', args.sides)):
        for v in values:
            key = {
                'drones': (int(v), p0, s0),
                'people': (n0, int(v), s0),
                'area': (n0, p0, float(v)),
            }[sweep]
            found.setdefault(key, []).append(sweep)
    for key, sweeps in found.items():  # the base point belongs to every sweep
        if key == (n0, p0, s0):
            sweeps[:] = list(SWEEPS)
    return [(*k, v) for k, v in found.items()]


def run_worker(folder: Path, people: int, args) -> dict:
    spec = {'folder': str(folder), 'people': people, 'tracker_frames': args.tracker_frames, 'seed': args.seed}
    proc = subprocess.run(
        [sys.executable, __file__, '--worker', json.dumps(spec)], capture_output=True, text=True, check=False
    )
    for line in proc.stdout.splitlines():
        if line.startswith('RESULT '):
            return json.loads(line[len('RESULT ') :])
    raise RuntimeError(f'worker for {folder} failed ({proc.returncode}):\n{proc.stderr[-3000:]}')


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--drones', type=int, nargs='*', default=[2, 4, 8, 12, 16], help='drone counts (1-16)')
    p.add_argument('--people', type=int, nargs='*', default=[10, 50, 100, 200], help='crowd sizes')
    p.add_argument('--sides', type=float, nargs='*', default=[15, 30, 45, 60], help='area sides (m)')
    p.add_argument(
        '--base',
        type=float,
        nargs=3,
        default=[8, 40, 30],
        metavar=('DRONES', 'PEOPLE', 'SIDE'),
        help='the point the sweeps vary one thing of',
    )
    p.add_argument('--frames', type=int, default=2, help='frames timed per point (one more is rendered and run first)')
    p.add_argument('--tracker_frames', type=int, default=40, help='tracker frames timed per point (after 10)')
    p.add_argument('--image_scale', type=float, default=0.5, help='drones render at this share of 1280 x 720')
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--out', default=str(ROOT / 'out/bench_scale'))
    p.add_argument('--worker', help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        return worker(args)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    results = []
    todo = points(args)
    for k, (drones, people, side, sweeps) in enumerate(todo):
        t = time.perf_counter()
        folder = render_point(out / 'sites', drones, people, side, args.frames, args.image_scale, args.seed)
        rendered = time.perf_counter() - t
        r = run_worker(folder, people, args)
        r.update(drones=drones, people=people, side=side, area_m2=side * side, sweeps=sweeps)
        results.append(r)
        print(
            f'[{k + 1}/{len(todo)}] {drones} drones, {people} people, {side:g} m: total {total(r):.0f} CPU ms per '
            f'frame (render {rendered:.0f} s, measure {time.perf_counter() - t - rendered:.0f} s)',
            file=sys.stderr,
            flush=True,
        )
    fits = growth(results)
    lines = acceptance(results, fits)
    first = results[0]
    header = (
        f'bench_scale: {os.cpu_count()} cores, {args.frames} frames per point at '
        f'{first["image_size"][0]}x{first["image_size"][1]} (image_scale {args.image_scale:g} of 1280x720), '
        f'tracker {args.tracker_frames} frames; sweeps around {int(args.base[0])} drones, {int(args.base[1])} '
        f'people, {args.base[2]:g} m; messages {"timed" if first["messages"] else "skipped (no ROS messages)"}'
    )
    page = markdown(results, fits, lines, header)
    print(page, end='')
    (out / 'scale.md').write_text(page)
    (out / 'scale.json').write_text(json.dumps({'results': results, 'growth': fits}, indent=1))
    figure(results, out / 'scale.png')
    print(f'wrote {out / "scale.md"}, {out / "scale.png"}, {out / "scale.json"} in {time.perf_counter() - start:.0f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
