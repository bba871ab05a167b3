"""A subscriber from another stack: it knows only the standard interfaces (vision_msgs, tf2_msgs, rclpy), none of
matrix-tracker's packages. Run as a process: ``python standard_subscriber.py OUT.json VIEW...``; it collects
``vision/tracks``, ``vision/detections``, each view's ``vision/detections_2d``, ``/tf`` and ``/tf_static``
(transient local: also what was published before it matched) until SIGTERM, then writes them as JSON with the
modules it had loaded."""

import json
import signal
import sys

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from tf2_msgs.msg import TFMessage
from vision_msgs.msg import Detection2DArray, Detection3DArray


def _stamp(header) -> float:
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def _3d(msg) -> dict:
    return {
        'stamp': _stamp(msg.header),
        'frame': msg.header.frame_id,
        'detections': [
            {
                'id': d.id,
                'xyz': [d.bbox.center.position.x, d.bbox.center.position.y, d.bbox.center.position.z],
                'size': [d.bbox.size.x, d.bbox.size.y, d.bbox.size.z],
                'class': [r.hypothesis.class_id for r in d.results],
                'score': [r.hypothesis.score for r in d.results],
            }
            for d in msg.detections
        ],
    }


def _2d(msg) -> dict:
    return {
        'stamp': _stamp(msg.header),
        'frame': msg.header.frame_id,
        'detections': [
            {
                'id': d.id,
                'center': [d.bbox.center.position.x, d.bbox.center.position.y],
                'size': [d.bbox.size_x, d.bbox.size_y],
                'score': [r.hypothesis.score for r in d.results],
            }
            for d in msg.detections
        ],
    }


def _tf(msg) -> list:
    return [
        {
            'stamp': _stamp(t.header),
            'parent': t.header.frame_id,
            'child': t.child_frame_id,
            'translation': [t.transform.translation.x, t.transform.translation.y, t.transform.translation.z],
            'rotation': [
                t.transform.rotation.x,
                t.transform.rotation.y,
                t.transform.rotation.z,
                t.transform.rotation.w,
            ],
        }
        for t in msg.transforms
    ]


def main(out: str, views: list) -> int:
    rclpy.init()
    node = rclpy.create_node('standard_subscriber')
    history = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    got = {'tracks': [], 'detections': [], 'tf': [], 'tf_static': [], **{f'{v}/detections_2d': [] for v in views}}
    node.create_subscription(Detection3DArray, 'vision/tracks', lambda m: got['tracks'].append(_3d(m)), history)
    node.create_subscription(Detection3DArray, 'vision/detections', lambda m: got['detections'].append(_3d(m)), history)
    node.create_subscription(TFMessage, '/tf', lambda m: got['tf'].extend(_tf(m)), history)
    node.create_subscription(TFMessage, '/tf_static', lambda m: got['tf_static'].extend(_tf(m)), history)
    for v in views:
        node.create_subscription(
            Detection2DArray,
            f'{v}/vision/detections_2d',
            lambda m, v=v: got[f'{v}/detections_2d'].append(_2d(m)),
            history,
        )
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(True))
    print('subscribed', flush=True)
    while not stop:
        rclpy.spin_once(node, timeout_sec=0.2)
    got['modules'] = sorted(m for m in sys.modules if m.split('.')[0].startswith('matrix'))
    with open(out, 'w') as f:
        json.dump(got, f)
    node.destroy_node()
    rclpy.shutdown()
    return 0


if __name__ == '__main__':
    raise SystemExit(main(sys.argv[1], sys.argv[2:]))
