"""The installed ``graph_monitor`` as the referee of a lockstep replay, over DDS: a frame is announced on
``/graph_monitor/frame_done`` only once every stage in ``wait_for`` processed it for every view, and a frame
that stays incomplete is named in a warning with exactly the parts it waits for (what a player's lockstep
timeout leaves unexplained otherwise)."""

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from matrix_msgs.msg import TrackArray
from rclpy.node import Node
from std_msgs.msg import Header

from matrix_core import topics
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.qos import publisher_qos, qos_by_name
from ros_helpers import spin_for, spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros]
STAMP = 1.0


def _status(publisher, stage: str, view: str) -> None:
    """One node's per-image status, as register and calib publish it."""
    publisher.publish(
        DiagnosticArray(
            header=Header(stamp=seconds_to_stamp(STAMP)),
            status=[DiagnosticStatus(name=f'{stage}/{view}', message='ok')],
        )
    )


def test_a_frame_is_done_only_when_every_part_arrived_and_a_late_one_is_named(node_executable, tmp_path):
    monitor = start_node(
        node_executable('matrix_bringup', 'graph_monitor'),
        'views:=[D1,D2]',
        'wait_for:=[register,calib,tracks]',
        'waiting_warning:=1.0',
        'idle_timeout:=120.0',
        f'out_dir:={tmp_path}',
    )
    rclpy.init()
    node = Node('referee_test')
    done = []
    diagnostics = node.create_publisher(DiagnosticArray, topics.DIAGNOSTICS_TOPIC, publisher_qos())
    tracks = node.create_publisher(TrackArray, topics.TRACKS, publisher_qos())
    frame_done = node.create_subscription(
        Header, topics.FRAME_DONE_TOPIC, lambda m: done.append(stamp_seconds(m.stamp)), qos_by_name('history')
    )
    try:
        wait_matched(node, [diagnostics, tracks, frame_done], [monitor], 60)
        for stage, view in [('register', 'D1'), ('register', 'D2'), ('calib', 'D1')]:
            _status(diagnostics, stage, view)
        tracks.publish(TrackArray(header=Header(stamp=seconds_to_stamp(STAMP), frame_id='world')))
        spin_for(node, 3.0)  # the time is the point: calib/D2 is missing, so nothing may be announced
        early = list(done)
        _status(diagnostics, 'calib', 'D2')
        announced = spin_until(node, lambda: STAMP in done, [monitor], 30)
    finally:
        out = stop(monitor)
        node.destroy_node()
        rclpy.shutdown()
    assert early == [], out
    assert announced and done == [STAMP], out
    warnings = [line for line in out.splitlines() if 'not done' in line]
    assert len(warnings) == 1 and 'frame t=1.000 s' in warnings[0], out
    assert warnings[0].endswith('waiting for calib/D2'), out


def test_a_monitor_stopped_by_sigterm_writes_its_summary_without_a_traceback(node_executable, tmp_path):
    # a benchmark or a launch stops the monitor while it still waits: it says what it saw, no traceback
    monitor = start_node(
        node_executable('matrix_bringup', 'graph_monitor'), 'views:=[D1]', 'expected_frames:=5', f'out_dir:={tmp_path}'
    )
    rclpy.init()
    node = Node('referee_stop_test')
    try:
        assert spin_until(node, lambda: 'graph_monitor' in node.get_node_names(), [monitor], 60)
    finally:
        node.destroy_node()
        rclpy.shutdown()
    out = stop(monitor)
    assert monitor.returncode == 1, out  # it could score nothing: no frame came
    assert 'Traceback' not in out and (tmp_path / 'graph_summary.txt').is_file(), out
