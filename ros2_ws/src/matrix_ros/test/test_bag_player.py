"""bag_player in its own process: a bag made from the real MATRIX sample replays over DDS unchanged,
with /clock, and lockstep holds each next frame until the graph acknowledges the previous one. The player
reads the sequence clock the bag stores (and numbers the frames of its log with it)."""

import time

import numpy as np
import pytest
import rclpy
from geometry_msgs.msg import PointStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, CompressedImage

from matrix_core.bags import SequenceClock, write_sequence_bag
from matrix_core.datasets import MatrixDataset
from matrix_core.message_fields import camera_from_camera_info, image_from_msg, stamp_seconds
from matrix_ros.qos import publisher_qos
from ros_helpers import finish, start_node

pytestmark = pytest.mark.ros


@pytest.fixture(scope='module')
def sample_bag(matrix_sample, tmp_path_factory):
    return write_sequence_bag(
        MatrixDataset(matrix_sample), tmp_path_factory.mktemp('bag') / 'sample', compressed=True, progress=False
    )


def _player(node_executable, bag, *params):
    return start_node(
        node_executable('matrix_ros', 'bag_player'),
        f'bag:={bag}',
        'topics:=[/D3/image/compressed,/D3/ground_truth/camera_info]',
        'wait_for_subscribers:=1',
        *params,
    )


def test_replay_is_unchanged_and_publishes_clock(matrix_sample, sample_bag, node_executable):
    ds = MatrixDataset(matrix_sample)
    got = {'img': [], 'info': [], 'clock': []}
    rclpy.init()
    node = rclpy.create_node('bag_test')
    node.create_subscription(CompressedImage, '/D3/image/compressed', got['img'].append, 10)
    node.create_subscription(CameraInfo, '/D3/ground_truth/camera_info', got['info'].append, 10)
    node.create_subscription(Clock, '/clock', got['clock'].append, 10)
    player = _player(node_executable, sample_bag, 'rate:=20.0')
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (
        min(len(got['info']), len(got['img']), len(got['clock'])) < 5 or player.poll() is None
    ):
        rclpy.spin_once(node, timeout_sec=0.1)
    out = finish(player, 30)
    node.destroy_node()
    rclpy.shutdown()
    assert player.returncode == 0, out
    assert len(got['img']) == 5 and len(got['info']) == 5, out
    for i, (img, info) in enumerate(zip(got['img'], got['info'])):
        assert stamp_seconds(info.header.stamp) == pytest.approx(1.0 + 0.5 * i)
        np.testing.assert_allclose(camera_from_camera_info(info).cam_T_world, ds.camera('D3', i).cam_T_world, atol=1e-9)
        decoded = image_from_msg(img).astype(float)
        assert np.abs(decoded - ds.load_image('D3', i)).mean() < 3.0  # JPEG of a JPEG
    assert [stamp_seconds(c.clock) for c in got['clock']][:5] == pytest.approx([1.0, 1.5, 2.0, 2.5, 3.0])
    assert 'sequence clock: first stamp 1 s, 0.5 s per frame' in out and 'stores no sequence clock' not in out
    assert 'played 5 frames up to frame 4 ' in out, out


def test_player_reads_the_clock_stored_in_the_bag(matrix_sample, node_executable, tmp_path):
    clock = SequenceClock(start_time=3.0, frame_period=0.25)
    bag = write_sequence_bag(
        MatrixDataset(matrix_sample), tmp_path / 'bag', compressed=True, clock=clock, progress=False
    )
    infos = []
    rclpy.init()
    node = rclpy.create_node('bag_clock_test')
    node.create_subscription(CompressedImage, '/D3/image/compressed', lambda m: None, 10)  # the player waits for it
    node.create_subscription(CameraInfo, '/D3/ground_truth/camera_info', infos.append, 10)
    player = _player(node_executable, bag, 'rate:=20.0')
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and (len(infos) < 5 or player.poll() is None):
        rclpy.spin_once(node, timeout_sec=0.1)
    out = finish(player)
    node.destroy_node()
    rclpy.shutdown()
    assert player.returncode == 0, out
    assert [stamp_seconds(i.header.stamp) for i in infos] == pytest.approx([clock.stamp(i) for i in range(5)])
    assert 'sequence clock: first stamp 3 s, 0.25 s per frame' in out and 'played 5 frames up to frame 4 ' in out, out


def _lockstep_run(node_executable, bag, *params):
    """Play ``bag`` in lockstep on /ack, acknowledging each frame 0.8 s after it arrived: (arrival times, ack
    times, the player's exit time, its output)."""
    arrivals, acks = [], []
    rclpy.init()
    node = rclpy.create_node('lockstep_test')
    ack = node.create_publisher(PointStamped, '/ack', publisher_qos())  # as the graph's nodes offer it
    node.create_subscription(CompressedImage, '/D3/image/compressed', lambda m: None, 10)
    node.create_subscription(
        CameraInfo, '/D3/ground_truth/camera_info', lambda m: arrivals.append((time.monotonic(), m.header)), 10
    )
    player = _player(
        node_executable,
        bag,
        'lockstep:=true',
        'lockstep_topic:=/ack',
        'lockstep_type:=geometry_msgs/msg/PointStamped',
        'lockstep_timeout:=20.0',
        *params,
    )
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and player.poll() is None:
        rclpy.spin_once(node, timeout_sec=0.05)
        if len(acks) < len(arrivals) and time.monotonic() - arrivals[len(acks)][0] > 0.8:
            ack.publish(PointStamped(header=arrivals[len(acks)][1]))  # "processed" 0.8 s after arrival
            acks.append(time.monotonic())
    exited = time.monotonic()
    out = finish(player, 5)
    node.destroy_node()
    rclpy.shutdown()
    assert player.returncode == 0 and len(arrivals) == 5 and len(acks) == 5, out
    assert 'lockstep: only' not in out
    return np.array([t for t, _ in arrivals]), np.array(acks), exited, out


def test_lockstep_waits_for_the_graph(sample_bag, node_executable):
    arrivals, _, _, _ = _lockstep_run(node_executable, sample_bag)
    gaps = np.diff(arrivals)
    assert np.all(gaps >= 0.75), gaps  # each frame waited for the acknowledgement of the previous one


def test_lockstep_window_keeps_two_frames_out(sample_bag, node_executable):
    """lockstep_window 2: frame k + 1 leaves before frame k is acknowledged, frame k + 2 only after; the player
    ends only once the last frame is acknowledged."""
    arrivals, acks, exited, out = _lockstep_run(node_executable, sample_bag, 'lockstep_window:=2')
    assert arrivals[1] - arrivals[0] < 0.5, arrivals - arrivals[0]  # not waiting for frame 0's ack (0.8 s)
    assert np.all(arrivals[2:] >= acks[:-2]), (arrivals - arrivals[0], acks - arrivals[0])
    assert np.all(arrivals[2:] - acks[:-2] < 0.5), (arrivals - arrivals[0], acks - arrivals[0])  # and soon after
    assert exited >= acks[-1], out


def test_start_at_releases_frames_together_and_skips_frames_due_before_ready(sample_bag, node_executable):
    """Players of several hosts (here: two processes, each with one drone's camera) given one ``start_at``
    publish each frame at the same time; a player ready after its frames were due skips them."""
    arrivals = {'D3': [], 'D5': []}
    rclpy.init()
    node = rclpy.create_node('start_at_test')
    for view, got in arrivals.items():
        node.create_subscription(
            CompressedImage, f'/{view}/image/compressed', lambda m, got=got: got.append(time.time()), 10
        )
    start_at = time.time() + 8.0  # the players are ready well before (a few seconds on a loaded machine)
    players = [
        start_node(
            node_executable('matrix_ros', 'bag_player'),
            f'bag:={sample_bag}',
            f'topics:=[/{view}/image/compressed]',
            'wait_for_subscribers:=1',
            f'start_at:={start_at}',
        )
        for view in arrivals
    ]
    late = start_node(
        node_executable('matrix_ros', 'bag_player'),
        f'bag:={sample_bag}',
        'topics:=[/D1/ground_truth/camera_info]',
        f'start_at:={time.time() - 10.0}',
    )  # every frame was due 8-10 s before it is ready
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and any(p.poll() is None for p in players):
        rclpy.spin_once(node, timeout_sec=0.02)
    outs = [finish(p, 10) for p in players]
    late_out = finish(late, 30)
    node.destroy_node()
    rclpy.shutdown()
    assert [p.returncode for p in players] == [0, 0], outs
    d3, d5 = np.array(arrivals['D3']), np.array(arrivals['D5'])
    assert len(d3) == len(d5) == 5, outs
    assert d3[0] >= start_at - 0.05 and np.abs(d3 - d5).max() < 0.3, (d3 - start_at, d5 - start_at)
    assert np.diff(d3) == pytest.approx(0.5, abs=0.2)  # the recorded timing from start_at on
    assert late.returncode == 1 and 'skipped 5 frames due before it was ready' in late_out, late_out


def test_a_bag_cut_short_plays_its_frames_before_the_cut_and_says_so(sample_bag, node_executable, tmp_path):
    """A copy of the sample bag cut in its second half: the whole frames before the cut are played,
    the player exits with code 4 and says where and why it stopped; no hang."""
    import shutil

    from matrix_core.bags.salvage import BagDamaged, mcap_file, raw_messages

    bag = tmp_path / 'cut'
    shutil.copytree(sample_bag, bag)
    f = mcap_file(bag)
    f.write_bytes(f.read_bytes()[: int(f.stat().st_size * 0.7)])
    times = []  # of the played topics' messages before the cut: a frame is whole once a later one began
    with pytest.raises(BagDamaged):
        times.extend(t for _, _, t, _ in raw_messages(bag, {'/D3/image/compressed', '/D3/ground_truth/camera_info'}))
    whole = sorted(set(times))[:-1]
    assert 1 <= len(whole) < 5, whole
    infos = []
    rclpy.init()
    node = rclpy.create_node('bag_cut_test')
    node.create_subscription(CompressedImage, '/D3/image/compressed', lambda m: None, 10)  # the player waits for it
    node.create_subscription(CameraInfo, '/D3/ground_truth/camera_info', infos.append, 10)
    player = _player(node_executable, bag, 'rate:=20.0')
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and player.poll() is None:
        rclpy.spin_once(node, timeout_sec=0.1)
    for _ in range(10):
        rclpy.spin_once(node, timeout_sec=0.1)
    out = finish(player, 10)
    node.destroy_node()
    rclpy.shutdown()
    assert player.returncode == 4, out
    assert [round(stamp_seconds(i.header.stamp) * 1e9) for i in infos] == whole, out
    assert 'messages before the damage' in out and 'stopping after the last whole frame before the damage' in out
    assert f'played {len(whole)} frames' in out, out
