#!/usr/bin/env python3
"""Soak benchmark: a long simulated sequence replayed through the whole graph in lockstep.

The graph and its probe are those of ``scripts/bench_graph.py`` (run_graph's processes, a probe on the first
drone's images and on ``/tracks``). While it runs, the resident memory (``VmRSS`` of /proc/PID/status, the
process and its children) of every process of the graph is sampled every ``--sample_s`` seconds. Reported:
frames lost (none expected), RSS per process at the start (first frame) and the end (last frame), per-frame
latency (first image -> tracks) over the first and the last 10 % of frames, as a table and a PNG of RSS and
latency over frames. A benchmark, not a CI test: 1000 frames take about 45 minutes on a 2-core machine.

    python scripts/bench_soak.py                    # 1000 frames, seed 7
    python scripts/bench_soak.py --frames 60        # a short run (a few minutes)
    python scripts/bench_soak.py --width 960 --height 540   # quarter-size images (4x faster to simulate)
"""

import argparse
import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np
import rclpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_graph import ROOT, Probe, simulated_sequence  # noqa: E402  (one graph benchmark)

from matrix_bringup.graph import BagFacts, GraphSettings, graph_nodes  # noqa: E402
from matrix_bringup.run_graph import Graph  # noqa: E402


def rss_mib(pid: int) -> float:
    """Resident memory of a process and its descendants in MiB (0 once it has exited)."""
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        try:
            for line in Path(f'/proc/{p}/status').read_text().splitlines():
                if line.startswith('VmRSS:'):
                    total += float(line.split()[1]) / 1024.0
            for task in Path(f'/proc/{p}/task').iterdir():
                todo += [int(c) for c in (task / 'children').read_text().split()]
        except (FileNotFoundError, ProcessLookupError, PermissionError):
            continue
    return total


def sample_rss(graph: Graph) -> dict:
    """label -> RSS (MiB) of every running process of the graph."""
    return {label: rss_mib(p.pid) for label, p in graph.procs.items() if p.poll() is None}


def frame_at(probe: Probe) -> int:
    """Frames whose tracks have arrived so far."""
    return len(probe.tracks)


def report(probe: Probe, samples: list, frames: int, out: Path) -> tuple:
    """Print the table; write soak.png. Returns (lost stamps, latencies (F,))."""
    stamps = sorted(probe.first_image)
    lost = [s for s in stamps if s not in probe.tracks]
    lat = np.array([probe.tracks[s] - probe.first_image[s] for s in stamps if s in probe.tracks])
    print(
        f'\nframes played / with tracks / in the bag: {len(stamps)} / {len(stamps) - len(lost)} / {frames}'
        + (f'  (lost: {lost[:10]}{" ..." if len(lost) > 10 else ""})' if lost else '  (no frame lost)')
    )
    if len(lat):
        span = max(probe.tracks.values()) - min(probe.first_image.values())
        print(f'sustained rate (lockstep): {len(lat) / span:.2f} frames/s')
        tenth = max(1, len(lat) // 10)
        first, last = lat[:tenth], lat[-tenth:]
        print(
            f'latency first image -> tracks: first {tenth} frames median {np.median(first):.2f} s '
            f'(p95 {np.percentile(first, 95):.2f}), last {tenth} frames median {np.median(last):.2f} s '
            f'(p95 {np.percentile(last, 95):.2f}), all median {np.median(lat):.2f} s'
        )
    started = [s for s in samples if s[0] >= 1]  # from the first frame with tracks: startup excluded
    if started:
        start = started[0]
        end = [s for s in started if set(s[2]) >= set(start[2])][-1]  # the last with every process running
        print(
            f'\n{"process":24s} {"RSS start MiB":>14s} {"RSS end MiB":>12s} {"change":>8s}   '
            f'(start = frame {start[0]}, end = frame {end[0]})'
        )
        for label in start[2]:
            a, b = start[2][label], end[2].get(label, float('nan'))
            print(f'{label:24s} {a:14.0f} {b:12.0f} {b - a:+8.0f}')
        a, b = sum(start[2].values()), sum(end[2].get(k, 0.0) for k in start[2])
        print(f'{"all":24s} {a:14.0f} {b:12.0f} {b - a:+8.0f}')
    plot(lat, started, out / 'soak.png')
    return lost, lat


def plot(lat: np.ndarray, samples: list, path: Path) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, (ax_rss, ax_lat) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    if samples:
        x = [s[0] for s in samples]
        for label in samples[0][2]:
            ax_rss.plot(x, [s[2].get(label, np.nan) for s in samples], label=label, lw=1)
        ax_rss.legend(fontsize=6, ncol=4)
    ax_rss.set_ylabel('RSS (MiB)')
    ax_rss.set_title('soak: resident memory per process and per-frame latency')
    ax_lat.plot(np.arange(1, len(lat) + 1), lat, lw=1)
    ax_lat.set_xlabel('frame')
    ax_lat.set_ylabel('latency first image -> tracks (s)')
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f'picture: {path}')


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--frames', type=int, default=1000)
    p.add_argument('--seed', type=int, default=7)
    p.add_argument('--width', type=int, default=1920, help='simulated image width (pixels)')
    p.add_argument('--height', type=int, default=1080, help='simulated image height (pixels)')
    p.add_argument('--drones_per_process', type=int, default=1, help='1 = one calib and one register process per drone')
    p.add_argument('--sample_s', type=float, default=2.0, help='seconds between RSS samples')
    p.add_argument('--out', default=str(ROOT / 'out/bench_soak'))
    args = p.parse_args()
    out = Path(args.out)
    bag, dataset = simulated_sequence(
        out / f'sim_{args.frames}_{args.seed}_{args.width}x{args.height}',
        args.frames,
        args.seed,
        (args.width, args.height),
    )
    run = out / 'run'
    shutil.rmtree(run, ignore_errors=True)
    settings = GraphSettings(
        bag=str(bag),
        dataset=str(dataset),
        drones_per_process=args.drones_per_process,
        checkpoint='',
        monitor=True,
        monitor_out=str(run / 'monitor'),  # '': the default
        record=str(run / 'recording'),
        lockstep_timeout=300.0,
    )
    facts = BagFacts.read(settings.bag, settings.views)
    specs = graph_nodes(settings, facts)
    player_label = specs[-1].label
    graph = Graph(run / 'logs', settings.dds_profile)
    rclpy.init()
    probe = Probe(settings.views[0], facts.compressed)
    samples = []  # (frames with tracks, wall s, {label: RSS MiB})
    t0 = time.monotonic()
    print(
        f'soak: {facts.frames} frames x {len(settings.views)} drones ({args.width}x{args.height}), '
        f'{len(specs)} processes, logs {run / "logs"}',
        flush=True,
    )
    try:
        for spec in specs:
            graph.start(spec)
        next_sample = next_print = 0.0
        while graph.procs[player_label].poll() is None and not graph.died(exclude=(player_label,)):
            probe.spin(0.2)
            now = time.monotonic() - t0
            if now >= next_sample:
                samples.append((frame_at(probe), now, sample_rss(graph)))
                next_sample = now + args.sample_s
            if now >= next_print:
                done, rss = samples[-1][0], sum(samples[-1][2].values())
                last = [
                    probe.tracks[s] - probe.first_image[s] for s in sorted(probe.tracks)[-5:] if s in probe.first_image
                ]
                print(
                    f'[{now:7.0f} s] frame {done}/{facts.frames}, RSS all {rss:.0f} MiB'
                    + (f', latency {np.median(last):.2f} s' if last else ''),
                    flush=True,
                )
                next_print = now + 30.0
        probe.spin(2.0)
        samples.append((frame_at(probe), time.monotonic() - t0, sample_rss(graph)))
        crashed = graph.died(exclude=(player_label, 'graph_monitor', 'recorder'))
    finally:
        graph.stop()
        probe.node.destroy_node()
        rclpy.try_shutdown()
    print(f'soak on {os.cpu_count()} cores, {time.monotonic() - t0:.0f} s wall')
    lost, _ = report(probe, samples, facts.frames, out)
    for label in crashed:
        print(f'{label} exited early; see {run / "logs"}')
    return 0 if not lost and not crashed and len(probe.first_image) == facts.frames else 1


if __name__ == '__main__':
    sys.exit(main())
