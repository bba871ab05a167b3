#!/usr/bin/env python3
"""Benchmark of the whole live graph on this machine: the processes of ``run_graph`` / ``full_graph.launch.py``
(bag_player -> one drone process per drone (calib + register; ``--separate``: one calib and one register
process each) -> fuse, with recorder and graph_monitor), separate processes over DDS, all sharing this
machine's cores, on JPEG bags of

- the real MATRIX sample (5 frames x 8 drones, 1920x1080; a JPEG bag of it is made once), and
- a seeded simulated complex sequence (``--frames``, default 40, x 8 drones, 1920x1080; made once),

each played in two ways:

- ``lockstep`` (throughput): the monitor releases the next frame once calib, register and fuse have all
  finished the last one; the rate is what the graph sustains;
- ``realtime`` (``--hz``, default 2 frames/s): the recorded timing, nothing waits; frames dropped (no tracks)
  and frames fused without every view say whether the graph keeps up.

A probe subscribes to the first drone's images, ``/tracks`` and the fuse node's diagnostics and measures per
frame the wall time from the frame's first image to its tracks (latency), to the last drone's registration (what
fuse waits for; printed per frame for short sequences) and to the last drone's calib status (calibration: nothing
in the graph waits for it, so it may come after the tracks). Every process's CPU time (user +
system from /proc, DDS and idle spinning included) between the first image and the last tracks, divided by
the frames, is each stage's CPU-s per frame (``drone``: calib + register of all drones). The probe also lists
the graph's topics: with JPEG bags no raw ``sensor_msgs/Image`` may cross DDS. ``--runs N`` repeats each
case and prints the medians. First, the CPU cost of decoding one of the bag's JPEGs on one core, as separate
calib and register processes do it (colour, then grey, each) and as the drone process does (grey once, then
register's resize).

    python scripts/bench_graph.py                              # both sequences, both modes, 1 run each
    python scripts/bench_graph.py --sequence sim --mode lockstep --runs 3
    python scripts/bench_graph.py --separate                   # the separate calib and register processes
    python scripts/bench_graph.py --register_params FILE       # e.g. register.yaml with mode: reference

Targets: 8 drones, 1080p JPEG bags, this 2-core machine: lockstep >= 2 frames/s (milestone
>= 1), realtime 2 Hz: no frame dropped, latency p95 <= 1 s.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import TrackArray
from sensor_msgs.msg import CompressedImage, Image

from matrix_bringup.graph import BagFacts, GraphSettings, graph_nodes
from matrix_bringup.run_graph import Graph
from matrix_core import topics
from matrix_core.bags.clock import read_sequence_clock
from matrix_core.message_fields import stamp_seconds
from matrix_ros.qos import qos_by_name

ROOT = Path(__file__).resolve().parent.parent
SHOW_FRAMES = 10  # sequences up to this long print every frame's latency


def simulated_sequence(out: Path, frames: int, seed: int = 11, size: tuple = (1920, 1080)) -> tuple:
    """(bag, dataset) of a seeded complex-variant sequence of ``size`` (width, height) pixels with a JPEG bag,
    made once."""
    if not (out / 'bag' / 'metadata.yaml').is_file():
        subprocess.run(
            [
                'matrix-tracker',
                'simulate',
                '--config',
                'complex',
                '--frames',
                str(frames),
                '--seed',
                str(seed),
                '--width',
                str(size[0]),
                '--height',
                str(size[1]),
                '--image_ext',
                '.jpg',
                '--bag',
                '--compressed',
                '--out',
                str(out),
            ],
            check=True,
        )
    return out / 'bag', out


def sample_sequence(out: Path, sample: Path) -> tuple:
    """(bag, dataset) of the real MATRIX sample with a JPEG bag, made once."""
    if not (out / 'metadata.yaml').is_file():
        shutil.rmtree(out, ignore_errors=True)
        subprocess.run(['matrix-tracker', 'bag', str(sample), '--out', str(out), '--compressed'], check=True)
    return out, sample


class Probe:
    """First arrival of each frame's image on one drone, arrival of each frame's tracks (wall clock), the
    views the fuse node used for each frame and how many calib and register statuses came for it."""

    def __init__(self, view: str, compressed: bool):
        self.node = rclpy.create_node('bench_graph_probe')
        self.first_image, self.tracks, self.views_used, self.drone_done, self.raw_topics = {}, {}, {}, {}, set()
        self.calibrated = {}  # stamp -> arrival of each drone's calib status
        self.registered = {}  # stamp -> arrival of each drone's register status
        kind = CompressedImage if compressed else Image
        topic = topics.image_topic(view, compressed)
        self.node.create_subscription(
            kind,
            topic,
            lambda m: self.first_image.setdefault(stamp_seconds(m.header.stamp), time.monotonic()),
            qos_by_name('reliable', 2),
        )
        self.node.create_subscription(
            TrackArray,
            topics.graph_topic(topics.TRACKS),
            lambda m: self.tracks.setdefault(stamp_seconds(m.header.stamp), time.monotonic()),
            qos_by_name('history', 100),
        )
        self.node.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS_TOPIC, self._on_diagnostics, qos_by_name('history', 100)
        )

    def _on_diagnostics(self, msg):
        for st in msg.status:
            if st.name.startswith(('calib/', 'register/')):
                stamp = stamp_seconds(msg.header.stamp)
                self.drone_done[stamp] = self.drone_done.get(stamp, 0) + 1
                arrivals = self.calibrated if st.name.startswith('calib/') else self.registered
                arrivals.setdefault(stamp, []).append(time.monotonic())
            elif st.name == 'fuse':
                self.views_used[stamp_seconds(msg.header.stamp)] = int(
                    next(kv.value for kv in st.values if kv.key == 'views_used')
                )

    def spin(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            rclpy.spin_once(self.node, timeout_sec=0.02)
        self.raw_topics |= {
            t
            for t, types in self.node.get_topic_names_and_types()  # published, not only subscribed
            if topics.IMAGE_TYPE in types and self.node.count_publishers(t)
        }


def stage_of(label: str) -> str:
    """'D3/calib', 'calib_2', 'D3/drone' -> 'calib', 'calib', 'drone'; other processes are their own stage."""
    name = label.split('/')[-1]
    return name.split('_')[0] if name.split('_')[0] in ('calib', 'register', 'drone') else name


def run_once(settings: GraphSettings, facts: BagFacts, run: Path, drain_s: float = 30.0) -> dict:
    """Play the bag through the graph once; the measured figures (see the module docstring)."""
    shutil.rmtree(run, ignore_errors=True)
    specs = graph_nodes(settings, facts)
    graph = Graph(run / 'logs', settings.dds_profile)
    probe = Probe(settings.views[0], facts.compressed)
    cpu_start = cpu_end = None
    try:
        for spec in specs:
            graph.start(spec)
        player, others = graph.procs[specs[-1].label], (specs[-1].label, 'graph_monitor', 'recorder')
        last_news, seen, stages = time.monotonic(), 0, 2 * len(settings.views)

        def news():  # outputs so far: tracks, calib's and register's statuses
            return len(probe.tracks) + sum(probe.drone_done.values())

        # until the player is done and every stage finished every frame (or nothing came for drain_s: dropped;
        # without lockstep fuse may fuse a frame before calib and register finished it)
        while not graph.died(exclude=others) and (
            player.poll() is None
            or (news() < len(probe.first_image) * (1 + stages) and time.monotonic() - last_news < drain_s)
        ):
            probe.spin(0.2)
            if cpu_start is None and probe.first_image:
                cpu_start = graph.cpu_seconds()  # processing starts; startup (imports, models) excluded
            if news() > seen:
                seen, last_news = news(), time.monotonic()
                cpu_end = graph.cpu_seconds()
        crashed = graph.died(exclude=others)
    finally:
        graph.stop()
        probe.node.destroy_node()
    stamps = sorted(probe.first_image)
    lat = np.array([probe.tracks[s] - probe.first_image[s] for s in stamps if s in probe.tracks])
    figures = {
        'played': len(stamps),
        'dropped': len([s for s in stamps if s not in probe.tracks]),
        'incomplete': sum(1 for s in stamps if probe.views_used.get(s, len(settings.views)) < len(settings.views)),
        'crashed': crashed,
        'raw_topics': sorted(probe.raw_topics),
        'timed_out': 'lockstep: only' in graph.log_path(specs[-1]).read_text(),
    }
    if len(lat) and cpu_start and cpu_end:
        figures['rate'] = len(lat) / (max(probe.tracks.values()) - min(probe.first_image.values()))
        figures['latency_median'], figures['latency_p95'] = np.median(lat), np.percentile(lat, 95)
        figures['latencies'] = lat.tolist()
        # the last registration of each frame: what fuse waits for (the rest of the latency is fuse's)
        figures['registered'] = [
            max(probe.registered[s]) - probe.first_image[s]
            if len(probe.registered.get(s, ())) == len(settings.views)
            else float('nan')
            for s in stamps
            if s in probe.tracks
        ]
        # calib: nothing in the graph waits for it (it may run behind the tracks: drone_link's own thread)
        calib = [
            max(probe.calibrated[s]) - probe.first_image[s]
            for s in stamps
            if len(probe.calibrated.get(s, ())) == len(settings.views)
        ]
        figures['calib_p95'] = np.percentile(calib, 95) if calib else float('nan')
        figures['calib_missing'] = len(settings.views) * len(stamps) - sum(
            len(probe.calibrated.get(s, ())) for s in stamps
        )
        stages = {}
        for label, end in cpu_end.items():
            stages[stage_of(label)] = stages.get(stage_of(label), 0.0) + (end - cpu_start.get(label, 0.0)) / len(lat)
        figures['cpu'] = stages
    return figures


def is_bad(run: dict) -> bool:
    """A run where a process died, the player timed out waiting for a frame, or a frame got no tracks."""
    return bool(run['crashed'] or run['timed_out'] or run['dropped'])


def decode_costs(bag: Path, repeats: int = 20) -> str:
    """CPU ms (this process, one OpenCV thread) per decode of the bag's first JPEG: each of the separate
    processes (colour + grey) and the drone process (grey + resize to register's scale 0.25)."""
    import cv2

    from matrix_core.bags.reader import read_bag
    from matrix_core.message_fields import gray_image_from_msg, image_from_msg

    msg = next(m.msg for m in read_bag(bag) if m.topic.endswith('/' + topics.IMAGE_COMPRESSED))
    cv2.setNumThreads(1)

    def ms(work):
        start = time.process_time()
        for _ in range(repeats):
            work()
        return (time.process_time() - start) / repeats * 1000

    separate = ms(lambda: cv2.cvtColor(image_from_msg(msg), cv2.COLOR_BGR2GRAY))
    once = ms(lambda: cv2.resize(gray_image_from_msg(msg), None, fx=0.25, fy=0.25, interpolation=cv2.INTER_AREA))
    return (
        f'decode of one {len(msg.data) / 1e3:.0f} kB JPEG (CPU, one thread): separate calib and register '
        f'2 x {separate:.1f} ms (colour + grey each), drone process {once:.1f} ms (grey once + resize)'
    )


def report(name: str, runs: list, views: int) -> int:
    """Print one case's figures (medians over runs); 1 when a run dropped or lost a frame or crashed."""

    def med(key):
        values = [r[key] for r in runs if key in r]
        return float(np.median(values)) if values else float('nan')

    # A process that exited before the last output (the player in real time, some runs) has no figure in that run.
    names = sorted({k for r in runs for k in r.get('cpu', {})})
    cpu = {k: float(np.median([r['cpu'][k] for r in runs if k in r.get('cpu', {})])) for k in names}
    total = sum(cpu.values())
    print(f'== {name} ({len(runs)} run{"s" if len(runs) > 1 else ""}, medians)')
    print(
        f'   frames played {med("played"):.0f}, dropped (no tracks) {med("dropped"):.0f}, fused without every '
        f'view {med("incomplete"):.0f}; rate {med("rate"):.2f} frames/s; latency first image -> tracks median '
        f'{med("latency_median"):.2f} s, p95 {med("latency_p95"):.2f} s; first image -> every drone\'s calib '
        f'status p95 {med("calib_p95"):.2f} s, statuses missing {med("calib_missing"):.0f}'
    )
    print(
        '   CPU s per frame: '
        + ', '.join(f'{k} {v:.2f}' for k, v in sorted(cpu.items(), key=lambda kv: -kv[1]))
        + f'; all {total:.2f} -> at most {os.cpu_count() / total:.2f} frames/s on {os.cpu_count()} cores'
        + (
            f'; per drone {(cpu.get("drone", 0) + cpu.get("calib", 0) + cpu.get("register", 0)) / views:.3f}'
            if total
            else ''
        )
    )
    short = [r['latencies'] for r in runs if 0 < len(r.get('latencies', ())) <= SHOW_FRAMES]
    if short:  # a short sequence: where its latency comes from (the first frame costs the most)
        print('   latency per frame (s), each run: ' + '; '.join(' '.join(f'{x:.2f}' for x in lat) for lat in short))
        print(
            '   of it, first image -> every drone\'s registration: '
            + '; '.join(
                ' '.join(f'{x:.2f}' for x in r['registered'])
                for r in runs
                if 0 < len(r.get('latencies', ())) <= SHOW_FRAMES
            )
        )
    raw = sorted({t for r in runs for t in r['raw_topics']})
    print(f'   raw images on DDS: {", ".join(raw) if raw else "none"}')
    bad = [r for r in runs if is_bad(r)]
    for r in bad:
        print(
            f'   WARNING: crashed {r["crashed"]}, lockstep timed out {r["timed_out"]}, dropped {r["dropped"]}'
            + (f'; logs: {r["logs"]}/' if 'logs' in r else '')
        )
    return 1 if bad else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--sequence', choices=('real', 'sim', 'both'), default='both')
    p.add_argument('--mode', choices=('lockstep', 'realtime', 'both'), default='both')
    p.add_argument('--runs', type=int, default=1, help='runs of each case; medians are printed')
    p.add_argument('--frames', type=int, default=40, help='frames of the simulated sequence')
    p.add_argument('--hz', type=float, default=2.0, help='frame rate of the realtime mode')
    p.add_argument('--separate', action='store_true', help='separate calib and register processes (drone_process off)')
    p.add_argument('--drones_per_process', type=int, default=1, help='1 = one process (or two: --separate) per drone')
    p.add_argument(
        '--drone_niceness',
        type=int,
        default=GraphSettings().drone_niceness,
        help='niceness of the drone processes (GraphSettings.drone_niceness; 0 = that of fuse)',
    )
    p.add_argument(
        '--dds_profile',
        default='',
        help="Fast DDS profile XML for every process ('' = the environment's, none = Fast DDS's own defaults)",
    )
    p.add_argument(
        '--register_params',
        default='',
        help="register's ROS parameter file (default: matrix_register/"
        "config/register.yaml, the live graph's: mode track); e.g. one with mode: reference to compare",
    )
    p.add_argument(
        '--fuse_params',
        default='',
        help="fuse's ROS parameter file (default: matrix_bev_tracker/config/fuse.yaml); e.g. one with threads: 2",
    )
    p.add_argument(
        '--lockstep_window',
        type=int,
        default=GraphSettings().lockstep_window,
        help='frames out at once in lockstep (GraphSettings.lockstep_window; 1 = one at a time)',
    )
    p.add_argument(
        '--lockstep_timeout',
        type=float,
        default=300.0,
        help='seconds the player waits for a frame to be done before going on (a WARNING line)',
    )
    p.add_argument('--checkpoint', default='', help='BEV checkpoint (default: the fuse node default)')
    p.add_argument('--sample', default=os.environ.get('MATRIX_SHARED', str(ROOT.parent / 'shared')) + '/matrix_sample')
    p.add_argument('--out', default=str(ROOT / 'out/bench_graph'))
    args = p.parse_args()
    out = Path(args.out)
    if args.dds_profile == 'none':  # the processes inherit this environment
        os.environ.pop('FASTRTPS_DEFAULT_PROFILES_FILE', None)
        args.dds_profile = ''
    sequences = {}
    if args.sequence in ('real', 'both'):
        sequences['real sample'] = sample_sequence(out / 'sample_bag', Path(args.sample))
    if args.sequence in ('sim', 'both'):
        sequences[f'simulated complex, {args.frames} frames'] = simulated_sequence(
            out / f'sim_{args.frames}', args.frames
        )
    modes = ['lockstep', 'realtime'] if args.mode == 'both' else [args.mode]
    print(
        f'whole graph on {os.cpu_count()} cores, 8 drones, JPEG bags, '
        + (
            'separate calib and register processes'
            if args.separate
            else 'one drone process (calib + register) per drone'
        )
        + f'; DDS profile {args.dds_profile or os.environ.get("FASTRTPS_DEFAULT_PROFILES_FILE", "(Fast DDS defaults)")}'
    )
    print(decode_costs(next(iter(sequences.values()))[0]))
    rclpy.init()
    code = 0
    try:
        for name, (bag, dataset) in sequences.items():
            period = read_sequence_clock(str(bag)).frame_period
            for mode in modes:
                settings = GraphSettings(
                    bag=str(bag),
                    dataset=str(dataset),
                    drones_per_process=args.drones_per_process,
                    drone_process=not args.separate,
                    checkpoint=args.checkpoint,
                    monitor=True,
                    monitor_out=str(out / 'run' / 'monitor'),
                    record=str(out / 'run' / 'recording'),
                    lockstep=mode == 'lockstep',
                    lockstep_timeout=args.lockstep_timeout,
                    rate=period * args.hz,
                    lockstep_window=args.lockstep_window,
                    dds_profile=args.dds_profile,
                    register_params=args.register_params,
                    fuse_params=args.fuse_params,
                    drone_niceness=args.drone_niceness,
                )
                facts = BagFacts.read(settings.bag, settings.views)
                label = mode if mode == 'lockstep' else f'realtime {args.hz:g} Hz'
                runs = []
                for i in range(args.runs):
                    runs.append(run_once(settings, facts, out / 'run'))
                    if is_bad(runs[-1]):  # the next run would overwrite the logs that say why
                        kept = out / 'failed' / f'{name}, {label}, run {i + 1}'.replace(' ', '_').replace(',', '')
                        shutil.rmtree(kept, ignore_errors=True)
                        shutil.copytree(out / 'run' / 'logs', kept)
                        runs[-1]['logs'] = str(kept)
                code |= report(f'{name}, {label}', runs, len(settings.views))
    finally:
        rclpy.try_shutdown()
    print(f'logs of the last run: {out / "run" / "logs"}/')
    return code


if __name__ == '__main__':
    sys.exit(main())
