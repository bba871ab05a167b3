"""``link_sender`` over DDS: the camera's frames cross to the link stream only as fast as the link budget lets
them, the others dropped whole at the sender (their headers on ``link/dropped``), each frame's outcome on
``/diagnostics``.

This test is the camera (publishes frames of 200 kB, several DDS fragments like an image) and reads
link_sender's statuses; the reader across the link is ``link_probe --link`` (what fuse reads, as fuse
reads it) in its own process."""

import signal
import subprocess
import sys
import time

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from matrix_bringup.distributed import read_probe
from matrix_core.link_gate import WIRE_OVERHEAD
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.qos import publisher_qos, qos_by_name
from ros_helpers import finish, spin_for, spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]
FRAME = bytes(range(256)) * 800  # 200 kB
LINK_MBIT = 1.6  # a frame takes the link 1.04 s
PERIOD_S = 0.25  # the camera: 4 frames/s, 6.4 Mbit/s


def test_frames_cross_as_fast_as_the_link_budget_lets_them(node_executable, tmp_path):
    rclpy.init()
    sender = start_node(node_executable('matrix_ros', 'link_sender'), 'views:=[D1]', f'link_mbit:={LINK_MBIT}')
    probe_log = tmp_path / 'probe.log'
    with open(probe_log, 'w') as log:
        log.write('link_probe --link D1\n')
        log.flush()
        reader = subprocess.Popen(
            [sys.executable, '-m', 'matrix_bringup.link_probe', '--link', 'D1'],
            stdout=log,
            stderr=subprocess.STDOUT,
            text=True,
        )
    node = Node('link_sender_test')
    said = {}  # stamp -> link_sender's status values

    def on_diagnostics(msg):
        for s in msg.status:
            if s.name == 'link_sender/D1':
                said[_rounded(msg.header.stamp)] = {kv.key: kv.value for kv in s.values}

    diag = node.create_subscription(DiagnosticArray, '/diagnostics', on_diagnostics, qos_by_name('history', 100))
    notices = []  # stamps of link_sender's notices of frames not sent
    dropped_sub = node.create_subscription(
        Header, '/D1/link/dropped', lambda m: notices.append(_rounded(m.stamp)), qos_by_name('reliable', 100)
    )
    camera = node.create_publisher(CompressedImage, '/D1/image/compressed', publisher_qos())
    stamps = iter(round(1.0 + 0.5 * k, 3) for k in range(1000))
    published_at = {}  # stamp -> monotonic s
    received = lambda: {round(line['stamp'], 3) for line in read_probe(probe_log) if line['kind'] == 'image'}  # noqa

    def play(count):
        """``count`` frames ``PERIOD_S`` apart (the timing is what is tested); their stamps."""
        played = []
        for _ in range(count):
            played.append(next(stamps))
            published_at[played[-1]] = time.monotonic()
            camera.publish(
                CompressedImage(
                    format='jpeg',
                    data=FRAME,
                    header=Header(stamp=seconds_to_stamp(played[-1]), frame_id='D1/camera_optical'),
                )
            )
            spin_for(node, PERIOD_S)
        spin_until(node, lambda: all(s in said for s in played), [sender], 10.0)
        return played

    try:
        wait_matched(node, [camera, diag, dropped_sub], [sender, reader])
        # until the reader matched link_sender's writer (a frame before that reaches nobody): a frame per 2 s
        warm_up = []
        while not received() and len(warm_up) < 30 and sender.poll() is None:
            warm_up += play(1)
            spin_for(node, 2.0 - PERIOD_S)  # the link free again
        assert received(), f'the reader never got a frame: {said}'
        spin_for(node, 1.5)
        played = play(16)
        spin_until(
            node,
            lambda: (
                received() >= {s for s in played if said[s]['outcome'] == 'sent'}
                and len(notices) >= sum(said[s]['outcome'] == 'dropped' for s in played)
            ),
            [sender],
            10.0,
        )
    finally:
        out = stop(sender)
        reader.send_signal(signal.SIGINT)
        finish(reader)
        rclpy.shutdown()

    outcomes = [said[s]['outcome'] for s in played]
    sent = [s for s in played if said[s]['outcome'] == 'sent']
    # about one frame in 4 or 5 crosses (1.04 s of link each, one every 0.25 s): the first, then each one that
    # came once the link had carried the last one sent, and no other (0.1 s: delivery jitter to link_sender)
    transfer = len(FRAME) * WIRE_OVERHEAD * 8 / (LINK_MBIT * 1e6)
    assert outcomes[0] == 'sent' and 3 <= len(sent) <= 5, (outcomes, out)
    since_sent, last = [], None
    for s in played:
        since_sent.append((said[s]['outcome'], published_at[s] - published_at[last] if last else None))
        last = s if said[s]['outcome'] == 'sent' else last
    assert all(dt > transfer - 0.1 for o, dt in since_sent[1:] if o == 'sent'), since_sent
    assert all(dt < transfer + 0.1 for o, dt in since_sent if o == 'dropped'), since_sent
    assert float(said[played[1]]['link_busy_s']) == pytest.approx(transfer - PERIOD_S, abs=0.2)
    assert int(said[played[-1]]['dropped']) == len(played) - len(sent)  # the warm-up's frames all left
    # what crossed is what link_sender said it sent, whole: never a dropped frame
    got = received()
    assert set(sent) <= got and not {s for s in played if s not in sent} & got, (got, outcomes)
    sizes = {line['bytes'] for line in read_probe(probe_log) if line['kind'] == 'image'}
    assert sizes == {len(FRAME)}
    # and the ground hears of each frame not sent, so that it need not wait for it
    assert sorted(notices) == sorted(s for s in said if said[s]['outcome'] == 'dropped')


def _rounded(stamp) -> float:
    return round(stamp_seconds(stamp), 3)
