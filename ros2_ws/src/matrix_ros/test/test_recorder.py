"""recorder in its own process: what the graph publishes ends up in a bag (readable by rosbags) and the
tracks in MOT-style text, and SIGTERM closes both cleanly. Frames published before the recorder existed
are recorded too (this workspace's publishers offer transient-local history; the recorder asks for it)."""

import signal
import subprocess
import time

import pytest
import rclpy
from geometry_msgs.msg import Point
from matrix_msgs.msg import Track, TrackArray
from sensor_msgs.msg import CameraInfo
from std_msgs.msg import Header

from matrix_core.bags import SequenceClock, bag_topics, read_bag, read_sequence_clock
from matrix_core.datasets import MatrixDataset
from matrix_ros.conversions import camera_to_camera_info, seconds_to_stamp
from matrix_ros.qos import publisher_qos
from ros_helpers import start_node, wait_matched

pytestmark = pytest.mark.ros


def test_records_standard_and_custom_messages(matrix_sample, node_executable, tmp_path):
    ds = MatrixDataset(matrix_sample)
    out = tmp_path / 'rec'

    def start_recorder():
        return start_node(
            node_executable('matrix_ros', 'recorder'),
            f'out:={out}',
            'topics:=[/D2/camera_info,/tracks]',
            'types:=[sensor_msgs/msg/CameraInfo,matrix_msgs/msg/TrackArray]',
            'tracks_topic:=/tracks',
        )

    procs = []
    try:
        _exercise(start_recorder, procs, ds)
    finally:
        for rec in procs:
            if rec.poll() is None:
                rec.kill()
                rec.communicate()
    lines = (tmp_path / 'rec.tracks.txt').read_text().split('\n')
    assert lines[:4] == ['0 7 1.0000 -2.0000', '0 9 5.0000 -6.5000', '1 7 2.0000 -2.0000', '1 9 5.0000 -7.5000']
    assert bag_topics(out) == {
        '/D2/camera_info': ('sensor_msgs/msg/CameraInfo', 3),
        '/tracks': ('matrix_msgs/msg/TrackArray', 3),
    }
    infos = [m.msg for m in read_bag(out, ['/D2/camera_info'])]
    assert list(infos[2].p) == pytest.approx(list(camera_to_camera_info(ds.camera('D2', 2)).p))
    assert read_sequence_clock(out) == SequenceClock()  # the clock that numbered the MOT frames, stored


def _exercise(start_recorder, procs, ds):
    """Publish two frames of CameraInfo and tracks, start the recorder, publish a third, then SIGTERM the
    recorder; it must have all three and exit cleanly."""
    rclpy.init()
    node = rclpy.create_node('recorder_test')
    try:
        info_pub = node.create_publisher(CameraInfo, '/D2/camera_info', publisher_qos())
        track_pub = node.create_publisher(TrackArray, '/tracks', publisher_qos())

        def publish(i):
            header = Header(stamp=seconds_to_stamp(1.0 + 0.5 * i), frame_id='world')
            info_pub.publish(camera_to_camera_info(ds.camera('D2', i), header))
            track_pub.publish(
                TrackArray(
                    header=header,
                    tracks=[
                        Track(id=7, position=Point(x=1.0 + i, y=-2.0)),
                        Track(id=9, position=Point(x=5.0, y=-6.5 - i)),
                    ],
                )
            )

        publish(0)
        publish(1)  # before the recorder exists
        procs.append(rec := start_recorder())
        wait_matched(node, [info_pub], [rec], 60)
        wait_matched(node, [track_pub], [rec], 60, count=2)  # the bag's subscription and the MOT text's
        publish(2)  # no wait for the recorder's side of the matching: history covers it
        for pub in (info_pub, track_pub):
            pub.wait_for_all_acked(rclpy.duration.Duration(seconds=5))
        # Acknowledged is received, not yet written, and the bag's writes cannot be seen from outside (it
        # is written on close): a fixed second for the recorder to take the third frame before SIGTERM.
        time.sleep(1.0)
        rec.send_signal(signal.SIGTERM)
        try:
            log = rec.communicate(timeout=30)[0]
        except subprocess.TimeoutExpired:
            rec.kill()
            pytest.fail('recorder did not exit on SIGTERM:\n' + rec.communicate()[0])
    finally:
        node.destroy_node()
        rclpy.shutdown()
    assert rec.returncode == 0, log


def test_clock_comes_from_the_sequence_bag_and_parameters_override_it(tmp_path):
    from matrix_core.bags import SequenceBagWriter
    from matrix_ros.recorder import RecorderSettings

    clock = SequenceClock(start_time=3.0, frame_period=0.25)
    with SequenceBagWriter(tmp_path / 'bag', ['D1'], clock=clock):
        pass
    assert RecorderSettings().clock() == SequenceClock()
    assert RecorderSettings(sequence_bag=str(tmp_path / 'bag')).clock() == clock
    assert RecorderSettings(sequence_bag=str(tmp_path / 'bag'), frame_period=1.0).clock() == SequenceClock(3.0, 1.0)
    assert RecorderSettings(start_time=0.0).clock() == SequenceClock(0.0, 0.5)


def test_a_killed_recorder_keeps_what_it_flushed(matrix_sample, node_executable, tmp_path):
    """SIGKILL mid-run: no metadata.yaml and no index are written, but every message received
    before the last flush is read back, then BagDamaged says the bag is unfinished; the MOT text is whole."""
    from matrix_core.bags import BagDamaged, raw_messages

    ds = MatrixDataset(matrix_sample)
    out = tmp_path / 'rec'
    rclpy.init()
    node = rclpy.create_node('recorder_kill_test')
    rec = None
    try:
        info_pub = node.create_publisher(CameraInfo, '/D2/camera_info', publisher_qos())
        track_pub = node.create_publisher(TrackArray, '/tracks', publisher_qos())
        rec = start_node(
            node_executable('matrix_ros', 'recorder'),
            f'out:={out}',
            'flush_period_s:=0.2',
            'topics:=[/D2/camera_info,/tracks]',
            'tracks_topic:=/tracks',
            'types:=[sensor_msgs/msg/CameraInfo,matrix_msgs/msg/TrackArray]',
        )
        wait_matched(node, [info_pub], [rec], 60)
        wait_matched(node, [track_pub], [rec], 60, count=2)
        for i in range(3):
            header = Header(stamp=seconds_to_stamp(1.0 + 0.5 * i), frame_id='world')
            info_pub.publish(camera_to_camera_info(ds.camera('D2', i), header))
            track_pub.publish(TrackArray(header=header, tracks=[Track(id=7, position=Point(x=1.0 + i, y=-2.0))]))
        for pub in (info_pub, track_pub):
            pub.wait_for_all_acked(rclpy.duration.Duration(seconds=5))
        time.sleep(1.5)  # received is not yet flushed: several flush periods
        rec.kill()
        rec.communicate(timeout=30)
    finally:
        if rec is not None and rec.poll() is None:
            rec.kill()
            rec.communicate()
        node.destroy_node()
        rclpy.shutdown()
    assert rec.returncode == -signal.SIGKILL and not (out / 'metadata.yaml').exists()
    got, infos = [], []
    with pytest.raises(BagDamaged, match=' 6 messages before the damage'):
        got.extend(topic for topic, _, _, _ in raw_messages(out))
    assert sorted(got) == ['/D2/camera_info'] * 3 + ['/tracks'] * 3
    with pytest.raises(BagDamaged, match=' 3 messages before the damage'):
        infos.extend(m.msg for m in read_bag(out, ['/D2/camera_info']))
    assert list(infos[2].p) == pytest.approx(list(camera_to_camera_info(ds.camera('D2', 2)).p))
    assert (tmp_path / 'rec.tracks.txt').read_text().split('\n')[:3] == [
        '0 7 1.0000 -2.0000',
        '1 7 2.0000 -2.0000',
        '2 7 3.0000 -2.0000',
    ]
