"""``python -m matrix_bringup.link_probe``: what a host of a distributed run sees, one JSON line per message on
stdout, each with the wall time it arrived (hosts of the harness share the machine's clock, so the lines of
probes on two hosts compare). For tests and scripts/bench_distributed.py.

    --fuse:          {"kind": "tracks", "stamp", "t", "ids"} per /tracks, {"kind": "fuse", "stamp", "t",
                     "views_used", "sync", "missing": {view: reason}} per fuse status on /diagnostics and
                     {"kind": "link", "view", "stamp", "t", "outcome"} per link_sender status there
    --images D1 D2:  {"kind": "image", "view", "stamp", "t", "bytes"} per /Dn/image/compressed (the camera's)
    --link D1 D2:    the same per /Dn/link/image/compressed (link_sender's, best effort as fuse reads it)
"""

import argparse
import json
import sys
import time

import rclpy
import rclpy.executors
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import TrackArray
from sensor_msgs.msg import CompressedImage

from matrix_core import topics
from matrix_core.message_fields import stamp_seconds
from matrix_ros.executor import spin_until
from matrix_ros.qos import qos_by_name


def _emit(**line) -> None:
    print(json.dumps({**line, 't': round(time.time(), 4)}), flush=True)


def _stamp(msg) -> float:
    return round(stamp_seconds(msg.header.stamp), 6)


def _values(status) -> dict:
    return {kv.key: kv.value for kv in status.values}


def _on_diagnostics(msg) -> None:
    by_name = {s.name: s for s in msg.status}
    for name, s in by_name.items():
        if name.startswith('link_sender/'):
            _emit(kind='link', view=s.hardware_id, stamp=_stamp(msg), outcome=_values(s)['outcome'])
    if 'fuse' not in by_name:
        return
    values = _values(by_name['fuse'])
    missing = {
        s.hardware_id: s.message for name, s in by_name.items() if name.startswith('fuse/') and s.message != 'used'
    }
    _emit(kind='fuse', stamp=_stamp(msg), views_used=int(values['views_used']), sync=values['sync'], missing=missing)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--fuse', action='store_true', help="fuse's tracks and diagnostics")
    parser.add_argument('--images', nargs='*', default=[], help="drones whose camera's images to log")
    parser.add_argument('--link', nargs='*', default=[], help="drones whose link_sender's images to log")
    args = parser.parse_args(argv)
    rclpy.init()
    node = rclpy.create_node('link_probe')
    if args.fuse:
        node.create_subscription(
            TrackArray,
            topics.TRACKS,
            lambda m: _emit(kind='tracks', stamp=_stamp(m), ids=[t.id for t in m.tracks]),
            qos_by_name('history', 100),
        )
        node.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS_TOPIC, _on_diagnostics, qos_by_name('history', 100)
        )
    for views, stream, qos in (
        (args.images, topics.IMAGE_COMPRESSED, 'sensor_data'),
        (args.link, topics.LINK_IMAGE_COMPRESSED, 'sensor_data'),
    ):
        for view in views:
            node.create_subscription(
                CompressedImage,
                topics.drone_topic(view, stream),
                lambda m, v=view: _emit(kind='image', view=v, stamp=_stamp(m), bytes=len(m.data)),
                qos_by_name(qos),
            )
    print(json.dumps({'kind': 'ready'}), flush=True)
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    try:
        spin_until(executor)  # SIGTERM and SIGINT through rclpy's handlers end it
    except KeyboardInterrupt:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
