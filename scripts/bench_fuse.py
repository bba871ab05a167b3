#!/usr/bin/env python3
"""Benchmark of the ``fuse`` node alone, as a separate process pinned to one core (torch threads 1), fed
over DDS by this script with 8 drones' streams of the real MATRIX sample (1920x1080 JPEG CompressedImage
+ HomographyStamped from the stored calibrations, frames cycled):

1. throughput: the next frame is published as soon as the tracks of the previous one arrived -> frames/s;
2. paced: frames published at ``--rate`` Hz (2 = the dataset's rate) stamped with the wall clock ->
   latency from image stamp to received tracks (median, p95) and frames lost.

    python scripts/bench_fuse.py [--frames 20] [--rate 2.0] [--cpu 0] [--raw]

Prints one table; targets: >= 2 frames/s on one core with p95 latency <= 1 s, and >= 5 frames/s for a drone graph
at 2 Hz on a small computer.
Besides wall-clock figures it prints the fuse process's CPU time per frame in the throughput phase (all its
threads, DDS included, from /proc): on a machine others load, 1 / that is the rate one free core would give.
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import HomographyStamped, TrackArray
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import Header
from tqdm import tqdm

from matrix_core import topics
from matrix_core.geometry.homography import pixel_scale_homography
from matrix_core.datasets import open_dataset
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import image_to_compressed, image_to_msg, seconds_to_stamp
from matrix_ros.qos import publisher_qos, qos_by_name

ROOT = Path(__file__).resolve().parent.parent


class Feeder:
    def __init__(self, dataset, raw: bool, scale: float):
        self.node = rclpy.create_node('bench_fuse_feeder')
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.views, qos = list(dataset.views), qos_by_name('reliable')
        kind = Image if raw else CompressedImage
        self.img_pubs = {
            v: self.node.create_publisher(kind, topics.image_topic(v, compressed=not raw), qos) for v in self.views
        }
        self.hom_pubs = {
            v: self.node.create_publisher(HomographyStamped, topics.absolute(v, topics.HOMOGRAPHY), publisher_qos())
            for v in self.views
        }
        self.received = {}  # stamp -> wall time the TrackArray arrived
        self.node.create_subscription(TrackArray, topics.graph_topic(topics.TRACKS), self._on_tracks, 100)
        self.stages = []  # the fuse node's own timing per frame (its /diagnostics)
        self.node.create_subscription(DiagnosticArray, topics.DIAGNOSTICS_TOPIC, self._on_diag, 100)
        # encode once: the bench times the fuse node, not this script
        self.frames = []
        for f in tqdm(dataset.frames, desc='encode', unit='frame', leave=False):
            imgs, homs = {}, {}
            for v in self.views:
                image = dataset.load_image(v, f)
                big_H_small = pixel_scale_homography(1 / scale, 1 / scale)
                if scale != 1:
                    image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
                imgs[v] = image_to_msg(image) if raw else image_to_compressed(image)
                H = np.linalg.inv(np.linalg.solve(big_H_small, dataset.camera(v, f).img_H_ground()))
                homs[v] = HomographyStamped(
                    status=HomographyStamped.OK, confidence=1.0, h_img_to_ground=(H / H[2, 2]).ravel().tolist()
                )
            self.frames.append((imgs, homs))

    def _on_tracks(self, msg):
        self.received[round(stamp_seconds(msg.header.stamp), 6)] = time.time()

    def _on_diag(self, msg):
        for st in msg.status:
            if st.name == 'fuse':
                self.stages.append({kv.key: kv.value for kv in st.values})

    def spin_until(self, cond, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not cond():
            self.executor.spin_once(timeout_sec=0.005)
        return cond()

    def publish(self, k: int, stamp: float):
        imgs, homs = self.frames[k % len(self.frames)]
        header = Header(stamp=seconds_to_stamp(stamp), frame_id='world')
        for v in self.views:
            imgs[v].header = header
            homs[v].header = header
            self.img_pubs[v].publish(imgs[v])
            self.hom_pubs[v].publish(homs[v])
        return round(stamp, 6)


def cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` so far (all its threads; /proc/PID/stat fields 14, 15)."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument(
        '--dataset', default=os.path.join(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared'), 'matrix_sample')
    )
    p.add_argument('--frames', type=int, default=20, help='frames per phase (default 20)')
    p.add_argument('--rate', type=float, default=2.0, help='paced phase rate, Hz (default 2)')
    p.add_argument('--cpu', type=int, default=0, help='core the fuse node is pinned to (default 0; -1: not pinned)')
    p.add_argument('--raw', action='store_true', help='raw sensor_msgs/Image instead of JPEG CompressedImage')
    p.add_argument(
        '--scale',
        type=float,
        default=1.0,
        help='resize the 1920x1080 images before sending '
        '(0.5: 960x540; shows how much of the latency is DDS transport of large images)',
    )
    p.add_argument(
        '--dds-profile',
        default=str(ROOT / 'ros2_ws/src/matrix_bringup/config/fastdds.xml'),
        help='Fast DDS profile for both processes (default: matrix_bringup/config/fastdds.xml; '
        '"" = the environment\'s / DDS defaults)',
    )
    p.add_argument('--checkpoint', default='', help='BEV checkpoint (default: the shipped one)')
    p.add_argument(
        '--exe',
        default=str(ROOT / 'ros2_ws/install/matrix_bev_tracker/lib/matrix_bev_tracker/fuse'),
        help='fuse executable (default: this workspace\'s; another checkout\'s for a before/after run, '
        'with that checkout\'s scripts/env.sh sourced)',
    )
    args = p.parse_args()
    dataset = open_dataset(args.dataset)
    if args.dds_profile:  # before rclpy.init: read when the DDS participants are created
        os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = args.dds_profile
    cmd = (['taskset', '-c', str(args.cpu)] if args.cpu >= 0 else []) + [
        args.exe,
        '--ros-args',
        '-p',
        'threads:=1',
        '-p',
        f'image_kind:={"raw" if args.raw else "compressed"}',
        '-p',
        'sync_timeout:=1.0',
        '-p',
        f'area:={list(map(float, dataset.area))}',
    ]
    if args.checkpoint:
        cmd += ['-p', f'checkpoint:={args.checkpoint}']
    rclpy.init()
    feeder = Feeder(dataset, args.raw, args.scale)
    fuse = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        pubs = [*feeder.img_pubs.values(), *feeder.hom_pubs.values()]
        if (
            not feeder.spin_until(
                lambda: fuse.poll() is not None or all(q.get_subscription_count() >= 1 for q in pubs), 120
            )
            or fuse.poll()
        ):
            raise RuntimeError('fuse node did not subscribe:\n' + (fuse.communicate()[0] if fuse.poll() else ''))
        # warm-up (first forward passes are slower), then throughput
        for k in range(3):
            s = feeder.publish(k, time.time())
            feeder.spin_until(lambda: s in feeder.received, 30)
        t0, done, cpu0 = time.monotonic(), 0, cpu_seconds(fuse.pid)
        for k in tqdm(range(args.frames), desc='throughput', unit='frame', leave=False):
            s = feeder.publish(k, time.time())
            done += feeder.spin_until(lambda: s in feeder.received, 30)
        throughput = done / (time.monotonic() - t0)
        cpu_per_frame = (cpu_seconds(fuse.pid) - cpu0) / max(done, 1)
        # paced at the dataset rate, stamps = wall clock -> latency image stamp -> tracks
        stamps, start = [], time.monotonic()
        for k in tqdm(range(args.frames), desc=f'paced {args.rate} Hz', unit='frame', leave=False):
            feeder.spin_until(lambda: time.monotonic() >= start + k / args.rate, 60)
            stamps.append(feeder.publish(k, time.time()))
        feeder.spin_until(lambda: all(s in feeder.received for s in stamps), 10)
        lat = np.array([feeder.received[s] - s for s in stamps if s in feeder.received])
    finally:
        fuse.terminate()
        log = fuse.communicate(timeout=30)[0]
        feeder.node.destroy_node()
        rclpy.try_shutdown()
    lost = len(stamps) - len(lat)
    print(
        f'fuse node alone, pinned to core {args.cpu}, torch threads 1, {len(feeder.views)} views '
        f'{round(1920 * args.scale)}x{round(1080 * args.scale)} '
        f'({"raw Image" if args.raw else "JPEG CompressedImage"}), {args.frames} frames per phase, '
        f'DDS profile: {args.dds_profile or os.environ.get("FASTRTPS_DEFAULT_PROFILES_FILE", "defaults")}'
    )
    print(f'{"throughput (lockstep)":28s} {throughput:6.2f} frames/s (wall clock)')
    print(
        f'{"fuse CPU time per frame":28s} {cpu_per_frame:6.3f} s -> {1 / cpu_per_frame:.2f} frames/s on one free core'
    )
    if len(lat):
        print(
            f'{"latency at " + str(args.rate) + " Hz":28s} median {np.median(lat):.3f} s, '
            f'p95 {np.percentile(lat, 95):.3f} s, max {lat.max():.3f} s'
        )
    print(f'{"frames lost at " + str(args.rate) + " Hz":28s} {lost} of {len(stamps)}')
    keys = ('decode_s', 'prepare_s', 'network_s', 'track_s', 'publish_s', 'wait_s')
    stages = [d for d in feeder.stages[3:] if all(k in d for k in keys)]
    if stages:
        print(
            'fuse node per frame (median s): '
            + ', '.join(f'{k[:-2]} {np.median([float(d[k]) for d in stages]):.3f}' for k in keys)
            + '  (wait: first message of a frame -> published)'
        )
    missing = [line for line in log.splitlines() if 'missing' in line]
    if missing:
        print(f'fuse node fused {len(missing)} frames without some views, e.g.: {missing[0][-160:]}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
