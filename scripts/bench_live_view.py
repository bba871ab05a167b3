#!/usr/bin/env python3
"""Benchmark of the live view's cost: CPU of the ``live_view`` process (matrix_live_view) while it serves what
a graph of 8 drones at 2 Hz publishes, with real images of the MATRIX sample.

This process publishes, per frame, what fuse and calib would (``tracks`` with ``--tracks`` people, the BEV
heatmap of the fuse node's grid size, and per drone its CameraInfo, its /tf pose and its 1920x1080 overlay
JPEG), at ``--rate`` Hz for ``--seconds``, in three rounds: no client; one Foxglove WebSocket client reading
everything; that client plus one that subscribes everything and never reads (its outbox fills: the live view
must drop, not queue). Prints the live view's CPU time over wall time (% of one core; psutil) per round, its
resident memory at the end of each, and how many messages the reading client got per second.

    python scripts/bench_live_view.py                     # 8 drones, 2 Hz, 20 s a round
    python scripts/bench_live_view.py --drones 4 --seconds 40
"""

import argparse
import asyncio
import json
import os
import socket
import sys
import threading
import time
from pathlib import Path

import cv2
import psutil
import rclpy
from geometry_msgs.msg import Point
from matrix_msgs.msg import Track, TrackArray
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import CameraInfo, CompressedImage
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / 'tests' / 'helpers'))

from foxglove_client import SUBPROTOCOLS, FoxgloveClient  # noqa: E402
from matrix_core import topics  # noqa: E402
from matrix_core.datasets import MatrixDataset  # noqa: E402
from matrix_core.datasets.base import read_image  # noqa: E402
from matrix_ros.conversions import camera_to_camera_info, camera_to_pose, seconds_to_stamp  # noqa: E402
from matrix_ros.qos import publisher_qos  # noqa: E402
from matrix_ros.vision_messages import pose_transform  # noqa: E402


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Feeder:
    """Publishes one frame of the graph's outputs that live_view reads, for ``views`` of the real sample."""

    def __init__(self, node, dataset: MatrixDataset, views: list, people: int):
        self.node, self.views, self.people, self.frame = node, views, people, 0
        qos = publisher_qos()
        self.cameras = {v: dataset.camera(v, 0) for v in views}
        self.jpegs = {v: cv2.imencode('.jpg', read_image(dataset.image_path(v, 0)))[1].tobytes() for v in views}
        self.pubs = {
            'tracks': node.create_publisher(TrackArray, topics.TRACKS, qos),
            'heatmap': node.create_publisher(OccupancyGrid, topics.BEV_HEATMAP, qos),
            'tf': node.create_publisher(TFMessage, topics.TF_TOPIC, qos),
            **{
                f'{v}/info': node.create_publisher(CameraInfo, topics.drone_topic(v, topics.CAMERA_INFO), qos)
                for v in views
            },
            **{
                f'{v}/overlay': node.create_publisher(
                    CompressedImage, topics.drone_topic(v, topics.OVERLAY_COMPRESSED), qos
                )
                for v in views
            },
        }

    def publish(self) -> None:
        self.frame += 1
        header = Header(stamp=seconds_to_stamp(1.0 + 0.5 * self.frame), frame_id=topics.WORLD_FRAME)
        tracks = [
            Track(id=k, score=0.8, position=Point(x=1.0 + (k * 0.9 + 0.1 * self.frame) % 28, y=-1.0 - k * 0.9))
            for k in range(self.people)
        ]
        self.pubs['tracks'].publish(TrackArray(header=header, tracks=tracks))
        grid = OccupancyGrid(header=header)
        grid.info.resolution, grid.info.width, grid.info.height = 0.25, 128, 128  # the fuse node's grid
        grid.info.origin.orientation.w = 1.0
        grid.data = bytes(128 * 128)
        self.pubs['heatmap'].publish(grid)
        for v in self.views:
            optical = Header(stamp=header.stamp, frame_id=topics.optical_frame(v))
            self.pubs[f'{v}/info'].publish(camera_to_camera_info(self.cameras[v], optical))
            pose = camera_to_pose(self.cameras[v], header)
            self.pubs['tf'].publish(TFMessage(transforms=[pose_transform(pose, optical.frame_id)]))
            self.pubs[f'{v}/overlay'].publish(CompressedImage(header=optical, format='jpeg', data=self.jpegs[v]))


def stalled_client(url: str, stop: threading.Event) -> threading.Thread:
    """A client that subscribes every channel and then never reads a byte."""
    import websockets

    async def run():
        async with websockets.connect(url, subprotocols=SUBPROTOCOLS, max_size=None) as ws:
            channels = []
            while len(channels) == 0:
                msg = json.loads(await ws.recv())
                if msg['op'] == 'advertise':
                    channels = msg['channels']
            subs = [{'id': i + 1, 'channelId': c['id']} for i, c in enumerate(channels)]
            await ws.send(json.dumps({'op': 'subscribe', 'subscriptions': subs}))
            ws.transport.pause_reading()  # nothing more is read: the server's outbox for it fills
            while not stop.is_set():
                await asyncio.sleep(0.1)

    thread = threading.Thread(target=lambda: asyncio.run(run()), daemon=True)
    thread.start()
    return thread


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        '--dataset', default=os.path.join(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared'), 'matrix_sample')
    )
    parser.add_argument('--drones', type=int, default=8)
    parser.add_argument('--tracks', type=int, default=30, help='people tracked per frame')
    parser.add_argument('--rate', type=float, default=2.0, help='frames per second')
    parser.add_argument('--seconds', type=float, default=20.0, help='length of each round')
    args = parser.parse_args()
    dataset = MatrixDataset(args.dataset)
    views = list(dataset.views)[: args.drones]
    port = _free_port()
    exe = ROOT / 'ros2_ws' / 'install' / 'matrix_live_view' / 'lib' / 'matrix_live_view' / 'live_view'
    import subprocess

    view = subprocess.Popen(
        [str(exe), '--ros-args', '-p', f'port:={port}', '-p', f'views:=[{",".join(views)}]'],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    rclpy.init()
    node = rclpy.create_node('bench_live_view')
    feeder = Feeder(node, dataset, views, args.tracks)
    proc = psutil.Process(view.pid)
    url = f'ws://127.0.0.1:{port}'
    print(f'live_view: {len(views)} drones, {args.tracks} tracks, {args.rate:g} Hz, {args.seconds:g} s a round')
    clients, stop = [], threading.Event()
    try:
        deadline = time.monotonic() + 60
        while not all(p.get_subscription_count() for p in feeder.pubs.values()):
            rclpy.spin_once(node, timeout_sec=0.1)
            if time.monotonic() > deadline or view.poll() is not None:
                raise SystemExit('live_view did not subscribe within 60 s')
        for name in ('no client', 'one client reading', 'and one stalled client'):
            if name == 'one client reading':
                clients.append(FoxgloveClient(url, keep=1))
                clients[0].connected.wait(30)
            elif name == 'and one stalled client':
                stalled_client(url, stop)
            time.sleep(1.0)
            received = sum(clients[0].counts.values()) if clients else 0
            cpu0, t0 = sum(proc.cpu_times()[:2]), time.monotonic()
            next_frame = t0
            while time.monotonic() - t0 < args.seconds:
                feeder.publish()
                next_frame += 1.0 / args.rate
                while time.monotonic() < next_frame:
                    rclpy.spin_once(node, timeout_sec=max(0.0, next_frame - time.monotonic()))
            wall, cpu = time.monotonic() - t0, sum(proc.cpu_times()[:2]) - cpu0
            rate = (sum(clients[0].counts.values()) - received) / wall if clients else 0.0
            print(
                f'  {name:24s} {100 * cpu / wall:5.1f} % of one core, rss {proc.memory_info().rss / 2**20:6.1f} MiB'
                + (f', reading client {rate:5.1f} messages/s' if clients else '')
            )
    finally:
        stop.set()
        for c in clients:
            c.close()
        view.terminate()
        view.wait(20)
        node.destroy_node()
        rclpy.shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
