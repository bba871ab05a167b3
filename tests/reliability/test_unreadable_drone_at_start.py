"""A drone whose reference image cannot be read (``echo x > reference/image_subsets/D2/0000.jpg`` in a copy of
the real sample) is left out of the whole graph at start and named; the other drones and fuse run and are
tracked as well as a graph without that drone (the offline evaluation of the same views: live == offline).
The nodes started on their own leave it out too (register, calib, the drone process: logged, on /diagnostics,
the other drone served; none left: exit 2 naming it), and fuse names it (no image boxes in that view)."""

import json
import os
import shutil
import subprocess

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from matrix_msgs.msg import Detection2DArray, HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage
from std_msgs.msg import Header

from matrix_core.bags import write_sequence_bag
from matrix_core.calib.scene import config_for_dataset
from matrix_core.cli.main import main as cli
from matrix_core.datasets import MatrixDataset
from matrix_core.datasets.drone_inputs import unreadable_drones
from matrix_ros.conversions import image_to_compressed, seconds_to_stamp
from matrix_ros.qos import publisher_qos, qos_by_name
from ros_helpers import finish, spin_until, start_node, stop, stop_all, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ['D1', 'D2', 'D5']


def broken_copy(sample, dst):
    """The sample as per-file links with D2's reference image replaced by two bytes of text."""
    shutil.copytree(sample, dst, copy_function=os.symlink)
    reference = dst / 'reference' / 'image_subsets' / 'D2' / '0000.jpg'
    reference.unlink()
    reference.write_text('x\n')
    return dst


def test_the_unreadable_drone_is_named(matrix_sample, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    problems = unreadable_drones(MatrixDataset(data), VIEWS)
    assert list(problems) == ['D2'] and 'cannot decode image' in problems['D2'] and '0000.jpg' in problems['D2']


def _run_graph(node_executable, bag, data, views, out):
    """run_graph on ``bag`` with ``data``'s reference: (completed process, node logs, live metrics)."""
    rec, logs = out / 'rec', out / 'logs'
    cmd = [str(node_executable('matrix_bringup', 'run_graph')), '--bag', str(bag), '--dataset', str(data)]
    cmd += ['--views', *views, '--record', str(rec), '--log_dir', str(logs), '--lockstep_timeout', '150']
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    node_logs = {p.name: p.read_text() for p in logs.glob('*.log')}
    live_json = out / 'live.json'
    scored = rec.exists() and cli(
        ['evaluate-recording', str(rec), '--ground-truth', str(bag), '--json', str(live_json)]
    )
    return run, node_logs, json.loads(live_json.read_text()) if scored == 0 else None


def test_run_graph_leaves_the_drone_out_and_tracks_the_others(matrix_sample, node_executable, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    bag = write_sequence_bag(MatrixDataset(matrix_sample), tmp_path / 'bag', compressed=True, progress=False)
    run, node_logs, live = _run_graph(node_executable, bag, data, VIEWS, tmp_path / 'broken')
    said = run.stdout + run.stderr
    assert run.returncode == 5, said + '\n'.join(f'== {k}\n{v[-3000:]}' for k, v in node_logs.items())
    assert 'D2 left out (reference: ' in said and 'ran without drone(s) D2' in said.splitlines()[-1], said
    assert sorted(node_logs) == ['D1_drone.log', 'D5_drone.log', 'bag_player.log', 'fuse.log', 'recorder.log']
    assert not any('Traceback' in text for text in node_logs.values())
    assert live['frames_without_tracks'] == []

    # the full graph with that view dropped, on the intact sample: the same tracking within 5 MODA points
    run, _, without = _run_graph(node_executable, bag, matrix_sample, ['D1', 'D5'], tmp_path / 'dropped')
    assert run.returncode == 0, run.stdout + run.stderr
    assert abs(live['detection']['moda'] - without['detection']['moda']) <= 0.05, (live, without)
    assert live['detection']['recall'] > 0.2  # two real views, the shipped checkpoint: people are found


# The nodes started on their own (outside run_graph and the launch), hosting D1 and D2 of the broken copy:
# D2 is left out, logged and reported on /diagnostics; D1 is served. A node with no drone left exits 2.
NODE_VIEWS = 'views:=[D1,D2]'


class Listener:
    """A test node collecting /diagnostics statuses by name, and D1's homographies and camera_infos."""

    def __init__(self):
        rclpy.init()
        self.node = Node('unreadable_drone_listener')
        self.statuses, self.homographies, self.infos = {}, [], []
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._diagnostics, qos_by_name('history', 100))
        self.node.create_subscription(HomographyStamped, '/D1/homography', self.homographies.append, 10)
        self.node.create_subscription(CameraInfo, '/D1/camera_info', self.infos.append, 10)

    def _diagnostics(self, msg):
        for status in msg.status:
            self.statuses.setdefault(status.name, status)

    def close(self):
        self.node.destroy_node()
        rclpy.shutdown()


def _left_out_status(status, level, message):
    """D2's start_up status: its level, its message (``message`` then the reason), the file in the reason."""
    why = {kv.key: kv.value for kv in status.values}['reason']
    assert status.level == level and status.hardware_id == 'D2', status
    assert status.message.startswith(f'{message}reference: cannot ') and 'D2/0000.jpg' in why, status


def test_register_and_calib_on_their_own_leave_the_drone_out(matrix_sample, node_executable, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    register = start_node(node_executable('matrix_register', 'register'), NODE_VIEWS, f'reference_dataset:={data}')
    calib = start_node(
        node_executable('matrix_calib', 'calib'),
        NODE_VIEWS,
        f'prior_dataset:={data}',
        f'config:={config_for_dataset(matrix_sample)}',
    )
    listener = Listener()
    try:
        names = ('register/D2/start_up', 'calib/D2/start_up')
        reported = spin_until(listener.node, lambda: set(names) <= set(listener.statuses), [register, calib], 120)
        alive = register.poll() is None and calib.poll() is None
    finally:
        listener.close()
        logs = stop_all([register, calib])
    said = '\n'.join(logs)
    assert reported and alive, said
    for name in names:
        _left_out_status(listener.statuses[name], DiagnosticStatus.ERROR, 'left out: ')
    assert not any(name.endswith('/D1/start_up') for name in listener.statuses), sorted(listener.statuses)
    for log, node in zip(logs, ('register', 'calib')):
        assert 'D2: left out at start (reference: cannot decode image' in log and 'serving D1' in log, log
        assert "['D1']" in log and 'Traceback' not in log, log  # the startup line lists the drone it serves


def test_a_drone_process_serves_the_other_drone(matrix_sample, node_executable, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    dataset = MatrixDataset(matrix_sample)
    drone = start_node(
        node_executable('matrix_bringup', 'drone'),
        NODE_VIEWS,
        'compressed:=true',
        f'reference_dataset:={data}',
        f'prior_dataset:={data}',
        f'config:={config_for_dataset(matrix_sample)}',
        'use_registration:=true',
        'registration_wait_s:=60.0',
    )
    listener = Listener()
    images = listener.node.create_publisher(CompressedImage, '/D1/image/compressed', qos_by_name('reliable'))
    try:
        wait_matched(listener.node, [images], [drone], 120)
        header = Header(stamp=seconds_to_stamp(1.0), frame_id='D1/camera_optical')
        images.publish(image_to_compressed(dataset.load_image('D1', dataset.frames[0]), header))
        served = spin_until(
            listener.node,
            lambda: listener.homographies and listener.infos and 'calib/D2/start_up' in listener.statuses,
            [drone],
            120,
        )
        alive = drone.poll() is None
    finally:
        listener.close()
        log = stop(drone)
    assert served and alive, log
    assert listener.homographies[0].status == HomographyStamped.OK, listener.homographies[0]
    for name in ('register/D2/start_up', 'calib/D2/start_up'):
        _left_out_status(listener.statuses[name], DiagnosticStatus.ERROR, 'left out: ')
    assert log.count('D2: left out at start') == 2 and 'Traceback' not in log, log


@pytest.mark.parametrize(
    'package, executable, inputs',
    [
        ('matrix_register', 'register', ['reference_dataset']),
        ('matrix_calib', 'calib', ['prior_dataset']),
        ('matrix_bringup', 'drone', ['reference_dataset', 'prior_dataset']),
    ],
)
def test_a_node_with_no_drone_left_exits_naming_it(
    package, executable, inputs, matrix_sample, node_executable, tmp_path
):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    config = [] if executable == 'register' else [f'config:={config_for_dataset(matrix_sample)}']
    node = start_node(
        node_executable(package, executable), 'views:=[D2]', *(f'{name}:={data}' for name in inputs), *config
    )
    log = finish(node, 120)
    assert node.returncode == 2, log
    assert 'error: ' in log and 'no drone can start: D2 left out (reference: cannot decode image' in log, log
    assert 'Traceback' not in log, log


def test_fuse_names_a_view_whose_reference_it_cannot_read(matrix_sample, node_executable, tmp_path):
    """fuse with the broken copy as its scene: D2's image boxes need the reference intrinsics it cannot read.
    It says so once at start and in every fused frame's /diagnostics; D1 is fused and boxed."""
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    dataset = MatrixDataset(matrix_sample)
    fuse = start_node(
        node_executable('matrix_bev_tracker', 'fuse'),
        NODE_VIEWS,
        f'scene_dataset:={data}',
        'image_kind:=compressed',
        'sync_timeout:=1.0',
    )
    listener = Listener()
    fused = []
    listener.node.create_subscription(
        DiagnosticArray,
        '/diagnostics',
        lambda m: fused.append(m) if any(s.name == 'fuse' for s in m.status) else None,
        10,
    )
    boxes = []
    listener.node.create_subscription(Detection2DArray, '/D1/detections_2d', boxes.append, 10)
    qos = qos_by_name('reliable')
    images = listener.node.create_publisher(CompressedImage, '/D1/image/compressed', qos)
    homographies = listener.node.create_publisher(HomographyStamped, '/D1/homography', publisher_qos())
    try:
        wait_matched(listener.node, [homographies], [fuse], 120)
        header = Header(stamp=seconds_to_stamp(1.0), frame_id='world')
        H = np.linalg.inv(dataset.camera('D1', dataset.frames[0]).img_H_ground())
        homography = HomographyStamped(header=header, status=HomographyStamped.OK, confidence=0.9)
        homography.h_img_to_ground = (H / H[2, 2]).ravel().tolist()
        homographies.publish(homography)
        wait_matched(listener.node, [images], [fuse], 120)  # images once the homography stream matched
        images.publish(image_to_compressed(dataset.load_image('D1', dataset.frames[0]), header))
        done = spin_until(listener.node, lambda: fused and boxes, [fuse], 120)
    finally:
        listener.close()
        log = stop(fuse)
    assert done, log
    status = {s.name: s for s in fused[0].status}
    _left_out_status(status['fuse/D2/start_up'], DiagnosticStatus.WARN, 'no image boxes: ')
    assert 'fuse/D1/start_up' not in status and status['fuse/D1'].message == 'used', status
    assert log.count('D2: no image boxes: reference: cannot read image header') == 1 and 'Traceback' not in log, log
