#!/usr/bin/env python3
"""Distributed deployment benchmark: the real sample over limited links, one host per drone.

Each drone host (a network namespace, matrix_bringup.netns_harness) runs its own camera (the bag player with
only its streams), register, calib and link_sender (the images it lets across, within ``--link_share`` of
the link rate: the others dropped whole at the sender); the ground host runs fuse and the recorder; every
drone's link is limited by ``tc tbf`` to ``--rate_mbit`` (one run per rate given) with a 1 MB queue. The
replay runs on the recorded timing (``--replay_rate`` 1 = 2 frames/s, the sample's clock), frames back and
forth over the sample's 5 frames. Reported per rate: bytes per frame per drone across its link (each
direction; the link counters from the first frame (1 s before) to the end divided by the frames played:
images, geometry, diagnostics, DDS announcements and acknowledgements), the JPEG bytes per image, frames
link_sender dropped per drone (whole, before the link), packets the limit dropped at the drones' end,
latency image -> tracks (the first drone's image arriving at its own host -> /tracks at the ground, wall
clock of one machine), frames with tracks, frames fused with all views and frames with an image lost (fuse
says 'no image' for a drone: dropped at the sender, on its link or later than the sync timeout). The first
drone's link is also captured (matrix_bringup.link_capture): its bytes per frame by DDS stream, each
direction.

``--find-min-rate``: the lowest link rate that keeps the replay rate: a run at the highest ``--rate_mbit``
(the reference), then a bisection down to ``--resolution`` Mbit/s, starting just above what the reference
measured a drone to send; a rate keeps it when at most ``--max_lost`` of the frames lost an image and the
p95 latency is at most ``--latency_margin`` s above the reference's (the margin isolates the link from this
machine's CPU load). A benchmark, not a CI test; needs root.

    python scripts/bench_distributed.py                                  # 8 drones, 20 Mbit/s, 40 frames
    python scripts/bench_distributed.py --rate_mbit 20 12 8              # one run per rate
    python scripts/bench_distributed.py --drones 2 --rate_mbit 8 --link_share 0   # no budget: the link drops
    python scripts/bench_distributed.py --drones 2 --frames 10 --find-min-rate   # the lowest rate at 2 Hz
    python scripts/bench_distributed.py --drones 2 --frames 10 --replay_rate 0.5   # a short run
    python scripts/bench_distributed.py --layout                         # what runs where, what crosses
"""

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def run_once(args, bag: Path, views: list, rate_mbit: float, out: Path) -> dict:
    from matrix_bringup.deployment import deployment
    from matrix_bringup.distributed import read_probe, start
    from matrix_bringup.graph import BagFacts, GraphSettings
    from matrix_bringup.netns_harness import GROUND, Hosts

    settings = GraphSettings(
        bag=str(bag),
        dataset=str(args.dataset),
        views=views,
        lockstep=False,
        rate=args.replay_rate,
        sync_timeout=args.sync_timeout,
        record=str(out / 'rec'),
    )
    d = deployment(settings, BagFacts.read(str(bag), views), link_mbit=args.link_share * rate_mbit)
    logs = out / 'logs'
    with Hosts(views, rate_mbit=rate_mbit, multicast=args.discovery == 'multicast') as hosts:
        procs = start(
            d, hosts, logs, args.discovery, image_probes=views[:1], captures=views[:1], player_lead_s=args.player_lead
        )
        time.sleep(max(0.0, args.player_lead - 1.0))  # to just before the first frame: count the replay only
        before = {v: hosts.link_bytes(v) for v in views}
        before_t = time.time()
        players = [p for label, p in procs.items() if label.endswith('bag_player')]
        deadline = time.monotonic() + args.timeout
        while any(p.poll() is None for p in players) and time.monotonic() < deadline:
            time.sleep(0.5)
        last = round(1.0 + 0.5 * (args.frames - 1), 6)  # the bag's sequence clock
        deadline = time.monotonic() + 30.0  # the last frame, queued on a slow link, is fused (or times out)
        while time.monotonic() < deadline and not any(
            line['kind'] == 'fuse' and line['stamp'] == last for line in read_probe(logs / 'ground_probe.log')
        ):
            time.sleep(0.5)
        time.sleep(1.0)  # the recorder writes it
        after = {v: hosts.link_bytes(v) for v in views}
        udp = hosts.udp_errors(GROUND)
        hosts.stop_all()
    played = len(args.frame_list)
    fused = {line['stamp']: line for line in read_probe(logs / 'ground_probe.log') if line['kind'] == 'fuse'}
    sender = [line for line in read_probe(logs / 'ground_probe.log') if line['kind'] == 'link']
    tracks = {line['stamp']: line['t'] for line in read_probe(logs / 'ground_probe.log') if line['kind'] == 'tracks'}
    images = {line['stamp']: line for line in read_probe(logs / f'{views[0]}_probe.log') if line['kind'] == 'image'}
    latency = np.array([tracks[s] - images[s]['t'] for s in images if s in tracks])
    captured = read_probe(logs / f'{views[0]}_capture.log')
    return {
        'streams': _per_frame(next(c for c in reversed(captured) if c['t'] <= before_t), captured[-1], played),
        'lost': sum(any('no image' in why for why in f['missing'].values()) for f in fused.values()),
        'rate_mbit': rate_mbit,
        'frames': played,
        'with_tracks': len(tracks),
        'sender_dropped': sum(line['outcome'] == 'dropped' for line in sender) / len(views),
        'all_views': sum(f['views_used'] == len(views) for f in fused.values()),
        'up_kb': np.mean([(after[v]['up'][0] - before[v]['up'][0]) / played / 1e3 for v in views]),
        'down_kb': np.mean([(after[v]['down'][0] - before[v]['down'][0]) / played / 1e3 for v in views]),
        'jpeg_kb': np.mean([i['bytes'] for i in images.values()]) / 1e3 if images else float('nan'),
        'dropped': sum(after[v]['dropped'] for v in views),
        'rcvbuf_errors': udp.get('RcvbufErrors', 0),
        'latency': latency,
        'players_ok': all(p.returncode == 0 for p in players),
    }


def _per_frame(first: dict, last: dict, frames: int) -> list:
    """The capture's totals between two of its lines, per frame: [(direction, peer, stream, kind, bytes)]."""
    key = ('direction', 'peer', 'stream', 'kind')
    start = {tuple(r[k] for k in key): r['bytes'] for r in first['streams']}
    rows = [
        (*(r[k] for k in key), (r['bytes'] - start.get(tuple(r[k] for k in key), 0)) / frames) for r in last['streams']
    ]
    return sorted((r for r in rows if r[-1] > 0), key=lambda r: (r[0] != 'down', -r[-1]))


def print_streams(row: dict, drone: str, smallest: float = 50.0) -> None:
    """What crossed ``drone``'s link per frame by stream, down then up; streams under ``smallest`` bytes a
    frame are summed per direction."""
    print(f"\nWhat crossed {drone}'s link at {row['rate_mbit']:g} Mbit/s, bytes per frame by stream (captured):")
    print('| direction | other end | stream | kind | bytes/frame |')
    print('| --- | --- | --- | --- | --- |')
    for direction in ('down', 'up'):
        rows = [r for r in row['streams'] if r[0] == direction]
        for d, peer, stream, kind, size in rows:
            if size >= smallest:
                print(f'| {d} | {peer} | {stream} | {kind} | {size:.0f} |')
        rest = [r[-1] for r in rows if r[-1] < smallest]
        if rest:
            print(f'| {direction} | | {len(rest)} smaller streams | | {sum(rest):.0f} |')
        print(f'| {direction} | | **total** | | **{sum(r[-1] for r in rows):.0f}** |')


def keeps(row: dict, reference: dict, args) -> bool:
    """The rate of ``row`` keeps the replay rate (see the module docstring)."""
    return (
        row['with_tracks'] == row['frames']
        and row['lost'] <= args.max_lost * row['frames']
        and len(row['latency']) > 0
        and np.percentile(row['latency'], 95) <= np.percentile(reference['latency'], 95) + args.latency_margin
    )


def find_min_rate(args, run) -> tuple:
    """Bisection over link rates (``run(rate) -> row``); returns (rows in run order, the lowest rate that kept
    the replay rate or None)."""
    reference = run(max(args.rate_mbit))
    rows, best = [reference], None
    if not keeps(reference, reference, args):
        return rows, None
    best = reference['rate_mbit']
    need = reference['up_kb'] * 8e-3 * 2 * args.replay_rate  # Mbit/s a drone sent at the reference
    low, high = 0.0, best
    rate = _round_up(1.1 * need, args.resolution)
    while high - low > args.resolution and len(rows) < args.max_runs:
        if not low < rate < high:
            rate = _round_up((low + high) / 2, args.resolution)
        if not low < rate < high:
            break
        row = run(rate)
        rows.append(row)
        if keeps(row, reference, args):
            high = best = rate
        else:
            low = rate
        rate = 0.0  # bisect from here on
    return rows, best


def _round_up(x: float, step: float) -> float:
    return float(np.ceil(x / step) * step)


def print_table(rows: list, views: list, args) -> None:
    print(
        f'\n{len(views)} drone hosts + ground, real sample frames back and forth, {len(args.frame_list)} frames '
        f'at {2 * args.replay_rate:g} frames/s, discovery {args.discovery}, sync_timeout {args.sync_timeout} s'
    )
    share = f'images within {args.link_share:.0%} of the link' if args.link_share else 'no image budget'
    print(f'{share} (link_sender)')
    print(
        '| Mbit/s per link | bytes/frame/drone up (down) | JPEG per image | frames dropped at the sender, per drone '
        '| tbf drops | latency image -> tracks median / p95 / max | frames with tracks | fused with all views '
        '| frames with an image lost |'
    )
    print('| --- | --- | --- | --- | --- | --- | --- | --- | --- |')
    for r in rows:
        lat = r['latency']
        lat_text = (
            f'{np.median(lat) * 1e3:.0f} / {np.percentile(lat, 95) * 1e3:.0f} / {lat.max() * 1e3:.0f} ms'
            if len(lat)
            else 'none'
        )
        print(
            f"| {r['rate_mbit']:g} | {r['up_kb']:.0f} kB ({r['down_kb']:.1f} kB) | {r['jpeg_kb']:.0f} kB | "
            f"{r['sender_dropped']:g}/{r['frames']} | {r['dropped']} | {lat_text} | {r['with_tracks']}/{r['frames']} | "
            f"{r['all_views']}/{r['frames']} | {r['lost']}/{r['frames']} |"
        )
    print(
        f"(ground UDP receive-buffer errors: {', '.join(str(r['rcvbuf_errors']) for r in rows)}; "
        f"players finished: {', '.join(str(r['players_ok']) for r in rows)})"
    )


def main(argv=None) -> int:
    from matrix_bringup.distributed import DISCOVERY, back_and_forth, write_replay_bag

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        '--dataset',
        type=Path,
        default=Path(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared')) / 'matrix_sample',
        help='the real sample (default: $MATRIX_SHARED/matrix_sample)',
    )
    parser.add_argument('--drones', type=int, default=8, help='drone hosts D1..Dn (default 8)')
    parser.add_argument('--rate_mbit', type=float, nargs='+', default=[20.0], help='link rates, one run each')
    parser.add_argument('--frames', type=int, default=40, help='frames replayed (default 40: 20 s at 2 Hz)')
    parser.add_argument('--replay_rate', type=float, default=1.0, help='1 = the recorded 2 frames/s')
    parser.add_argument('--sync_timeout', type=float, default=1.0, help="fuse's wait for a late view (s)")
    parser.add_argument(
        '--link_share',
        type=float,
        default=0.9,
        help="share of each link's rate the images may use (link_sender's budget; the rest: "
        'geometry, diagnostics, discovery); 0: no budget, every frame is sent',
    )
    parser.add_argument(
        '--discovery',
        choices=tuple(DISCOVERY),
        default='multicast',
        help='how hosts find each other (matrix_bringup.distributed.DISCOVERY)',
    )
    parser.add_argument(
        '--find-min-rate',
        dest='find_min_rate',
        action='store_true',
        help='search the lowest link rate that keeps the replay rate (module docstring)',
    )
    parser.add_argument('--resolution', type=float, default=1.0, help='Mbit/s the search stops at')
    parser.add_argument('--max_runs', type=int, default=5, help='runs the search may take, the reference included')
    parser.add_argument('--max_lost', type=float, default=0.1, help='share of frames that may lose an image')
    parser.add_argument(
        '--latency_margin', type=float, default=0.5, help='s the p95 latency may exceed the reference run'
    )
    parser.add_argument('--timeout', type=float, default=600.0, help='seconds a run may take')
    parser.add_argument(
        '--player_lead',
        type=float,
        default=5.0,
        help='s from every player ready (matrix_bringup.start_signal) to the first frame: the delivery of the '
        'start time to the players',
    )
    parser.add_argument('--out', type=Path, default=ROOT / 'out' / 'bench_distributed')
    parser.add_argument('--layout', action='store_true', help='print what runs where and what crosses each link')
    args = parser.parse_args(argv)

    from matrix_bringup.netns_harness import unavailable
    from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS

    views = list(MATRIX_VIEWS)[: args.drones]
    args.frame_list = back_and_forth(5, args.frames)
    if args.layout:
        from matrix_bringup.deployment import deployment
        from matrix_bringup.graph import BagFacts, GraphSettings

        facts = BagFacts(compressed=True, frames=args.frames, has_ground_truth=True)
        print(
            deployment(GraphSettings(bag='BAG', dataset=str(args.dataset), views=views, record='REC'), facts).describe()
        )
        return 0
    reason = unavailable()
    if reason:
        print(f'bench_distributed: skipped: {reason}')
        return 0
    bag = args.out / f'bag_{len(views)}drones_{args.frames}frames'
    if not bag.exists():
        args.out.mkdir(parents=True, exist_ok=True)
        write_replay_bag(args.dataset, bag, views, args.frame_list)

    def run(rate):
        run_dir = args.out / f'{rate:g}mbit_{time.strftime("%H%M%S")}'
        row = run_once(args, bag, views, rate, run_dir)
        print(
            f'{rate:g} Mbit/s: logs in {run_dir}/logs; {row["lost"]}/{row["frames"]} frames lost an image', flush=True
        )
        return row

    if args.find_min_rate:
        rows, best = find_min_rate(args, run)
    else:
        rows = [run(rate) for rate in args.rate_mbit]
    print_table(rows, views, args)
    print_streams(rows[0], views[0])
    if args.find_min_rate:
        print(
            f'\nlowest rate that keeps {2 * args.replay_rate:g} frames/s (at most {args.max_lost:.0%} of frames '
            f'losing an image, p95 latency within {args.latency_margin:g} s of the {rows[0]["rate_mbit"]:g} Mbit/s '
            'run): '
            + (
                f'{best:g} Mbit/s per link'
                if best is not None
                else f'none: the reference run at {rows[0]["rate_mbit"]:g} Mbit/s did not keep it'
            )
        )
    return 0


if __name__ == '__main__':
    sys.exit(main())
