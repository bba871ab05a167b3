#!/usr/bin/env python3
"""Benchmark of the whole graph on this machine: bag_player -> calib (8 drones) + register (8 drones) ->
fuse (on the registration homographies) in lockstep on ``/tracks``, every node its own process over DDS,
all sharing this machine's cores. A probe subscribes to ``/D1/image_raw`` and ``/tracks`` and measures,
per frame, the wall time from the frame's first image to its tracks (latency) and the frames/s that
lockstep sustains; every node's log says what it spent. Lockstep must lose no frame.

    python scripts/bench_graph.py [--bag out/demo/matrix_sample_bag] [--dataset ../shared/matrix_sample]

(`make demo` writes the bag of the real sample; ``matrix-tracker bag DATASET --out BAG`` makes any other.)
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import rclpy
from matrix_msgs.msg import TrackArray
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Image

from matrix_ros.conversions import stamp_to_seconds

ROOT = Path(__file__).resolve().parent.parent
VIEWS = '[D1,D2,D3,D4,D5,D6,D7,D8]'


def node(pkg: str, exe: str, *params: str) -> list:
    args = [str(ROOT / f'ros2_ws/install/{pkg}/lib/{pkg}/{exe}'), '--ros-args']
    for p in params:
        args += ['-p', p]
    return args


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    shared = Path(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared'))
    p.add_argument('--bag', default=str(ROOT / 'out/demo/matrix_sample_bag'))
    p.add_argument('--dataset', default=str(shared / 'matrix_sample'), help='references and calibration prior')
    args = p.parse_args()
    if not (Path(args.bag) / 'metadata.yaml').is_file():
        subprocess.run(['matrix-tracker', 'bag', args.dataset, '--out', args.bag], check=True)
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for cmd in (
        node('matrix_calib', 'calib', f'views:={VIEWS}', f'prior_dataset:={args.dataset}', 'qos:=reliable'),
        node('matrix_register', 'register', f'views:={VIEWS}', f'reference_dataset:={args.dataset}'),
        node('matrix_bev_tracker', 'fuse', 'input_kind:=homography', 'sync_timeout:=60.0', 'use_sim_time:=true'))]
    rclpy.init()
    probe = rclpy.create_node('bench_graph_probe')
    first_image, tracks = {}, {}
    probe.create_subscription(Image, '/D1/image_raw',
                              lambda m: first_image.setdefault(stamp_to_seconds(m.header.stamp), time.time()),
                              qos_profile_sensor_data)
    probe.create_subscription(TrackArray, '/tracks',
                              lambda m: tracks.setdefault(stamp_to_seconds(m.header.stamp), time.time()), 100)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and probe.count_publishers('/tracks') < 1:
        rclpy.spin_once(probe, timeout_sec=0.1)
    time.sleep(3)   # the nodes' own subscriptions match
    player = subprocess.Popen(node('matrix_ros', 'bag_player', f'bag:={args.bag}', 'wait_for_subscribers:=3',
                                   'lockstep:=true', 'lockstep_topic:=/tracks',
                                   'lockstep_type:=matrix_msgs/msg/TrackArray', 'lockstep_timeout:=120.0'),
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    while player.poll() is None:
        rclpy.spin_once(probe, timeout_sec=0.05)
    end = time.monotonic() + 3
    while time.monotonic() < end:
        rclpy.spin_once(probe, timeout_sec=0.05)
    player_log = player.communicate()[0]
    for q in procs:
        q.terminate()
    logs = [q.communicate(timeout=30)[0] for q in procs]
    probe.destroy_node()
    rclpy.try_shutdown()

    stamps = sorted(first_image)
    lat = np.array([tracks[s] - first_image[s] for s in stamps if s in tracks])
    lost = [s for s in stamps if s not in tracks]
    span = max(tracks.values()) - min(first_image.values()) if tracks else float('nan')
    print(f'whole graph on {os.cpu_count()} cores: player + calib (8 drones) + register (8 drones) + fuse, lockstep')
    print(f'{"frames played / with tracks":30s} {len(stamps)} / {len(stamps) - len(lost)}'
          + (f'  (lost: {lost})' if lost else '  (no frame lost)'))
    if len(lat):
        print(f'{"sustained rate (lockstep)":30s} {len(lat) / span:.2f} frames/s')
        print(f'{"latency image -> tracks":30s} median {np.median(lat):.2f} s, p95 {np.percentile(lat, 95):.2f} s')
    print('per-stage time per frame on one core: python scripts/bench_calib.py, bench_register.py, bench_fuse.py')
    if 'lockstep: only' in player_log:
        print('WARNING: lockstep timed out for some frames:\n' + player_log)
    for name, log in zip(('calib', 'register', 'fuse'), logs):
        errors = [line for line in log.splitlines() if 'Traceback' in line]
        if errors:
            print(f'{name} crashed:\n{log[-2000:]}')
    return 0 if not lost else 1


if __name__ == '__main__':
    sys.exit(main())
