"""The installed ``calib`` node, in its own process, calibrates real MATRIX images that another process
(``dataset_player``) publishes over DDS; this test process checks its CameraInfo, pose and diagnostics
against the stored calibration, and that corrupt input is logged without stopping the node."""

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage

from matrix_core.calib.status import CalibStatus
from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.message_fields import camera_from_camera_info, stamp_seconds
from matrix_ros.conversions import pose_to_world_T_cam
from matrix_ros.qos import qos_by_name
from ros_helpers import spin_until, start_node, stop, stop_all, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ('D1', 'D5')  # two drones hosted by one calib process
FRAMES = 5  # frames published, each must come back (ok, or stale with its age)
PUBLISHED = FRAMES
STARTUP_S = 120  # a node process starts and matches in seconds, minutes on a loaded machine


def test_calib_node_matches_stored_calibration(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    rclpy.init()
    node = Node('calib_test_listener')
    got = {(v, kind): [] for v in VIEWS for kind in ('info', 'pose')}
    diags = []
    outputs = []
    for v in VIEWS:
        outputs += [
            node.create_subscription(CameraInfo, f'/{v}/camera_info', lambda m, v=v: got[(v, 'info')].append(m), 10),
            node.create_subscription(PoseStamped, f'/{v}/pose', lambda m, v=v: got[(v, 'pose')].append(m), 10),
        ]
    node.create_subscription(DiagnosticArray, '/diagnostics', diags.append, 50)
    calib = start_node(
        node_executable('matrix_calib', 'calib'),
        f'views:=[{",".join(VIEWS)}]',
        f'prior_dataset:={matrix_sample}',
        'qos:=reliable',
        # intrinsics (only K, D, size) from the player's stored CameraInfo, as a drone driver sends
        'intrinsics_topic:=ground_truth/camera_info',
    )
    processes = [calib]
    try:
        # Start the images only once calib's outputs are matched to this listener: results published before
        # discovery finishes would be lost (volatile durability), and the tracker would start mid-sequence.
        wait_matched(node, outputs, [calib], STARTUP_S)
        processes.insert(
            0,
            start_node(
                node_executable('matrix_ros', 'dataset_player'),
                f'dataset:={matrix_sample}',
                f'views:=[{",".join(VIEWS)}]',
                f'max_frames:={PUBLISHED}',
                'rate:=0.4',
                'wait_for_subscribers:=1',
            ),
        )
        spin_until(
            node,
            lambda: all(len(x) >= FRAMES for x in got.values()) and len(diags) >= len(VIEWS) * FRAMES,
            processes,
            120,
        )
    finally:
        out = '\n'.join(stop_all(processes))  # the player first
        node.destroy_node()
        rclpy.shutdown()
    status_of = {(st.hardware_id, stamp_seconds(d.header.stamp)): st for d in diags for st in d.status}
    for v in VIEWS:
        infos, poses = got[(v, 'info')], got[(v, 'pose')]
        assert len(infos) >= FRAMES and len(poses) >= FRAMES, f'{v}: missing output; processes said:\n{out}'
        ok = 0
        for info, pose in zip(infos, poses):
            assert info.header.stamp == pose.header.stamp
            stamp = stamp_seconds(info.header.stamp)
            index = int(round((stamp - 1.0) / 0.5))  # the player stamps frame i with 1.0 s + 0.5 s * i
            status = status_of.get((v, stamp))
            assert status is not None, f'{v}: no diagnostics for the image stamped {stamp}'
            cam = camera_from_camera_info(info)
            assert np.all(np.isfinite(info.p))
            np.testing.assert_allclose(pose_to_world_T_cam(pose), cam.world_T_cam, atol=1e-6)
            truth = dataset.camera(v, dataset.frames[index])
            np.testing.assert_allclose(cam.K, truth.K, atol=0.05)
            if status.message.startswith('ok') or status.level == DiagnosticStatus.OK:
                ok += 1
                assert rotation_angle_deg(cam.R, truth.R) < 0.5, f'{v} frame {index}'
                assert np.linalg.norm(cam.center - truth.center) < 0.3, f'{v} frame {index}'
            else:  # stale: the last good pose, with its age
                age = float({kv.key: kv.value for kv in status.values}['age_s'])
                assert status.level == DiagnosticStatus.WARN and age >= 0.5
        assert ok >= FRAMES - 1, f'{v}: only {ok} fresh poses; processes said:\n{out}'
    assert 'intrinsics from ground_truth/camera_info' in out, out
    statuses = [s for d in diags for s in d.status if s.name.startswith('calib/')]
    assert len(statuses) >= len(VIEWS) * FRAMES
    keys = {kv.key for kv in statuses[0].values}
    assert {'status', 'reprojection_rms_px', 'corners', 'age_s', 'latency_s'} <= keys


def test_calib_node_survives_bad_input(matrix_sample, node_executable):
    rclpy.init()
    node = Node('calib_bad_input_test')
    pub = node.create_publisher(CompressedImage, '/D5/image/compressed', 10)
    diags = []
    # history: the calib's first status may go out before its writer matched this reader
    diag_sub = node.create_subscription(DiagnosticArray, '/diagnostics', diags.append, qos_by_name('history'))
    calib = start_node(
        node_executable('matrix_calib', 'calib'),
        'views:=[D5]',
        'compressed:=true',
        f'prior_dataset:={matrix_sample}',
        'qos:=reliable',
    )
    good = (matrix_sample / 'image_subsets/D5/0000.jpg').read_bytes()
    try:
        wait_matched(node, [pub, diag_sub], [calib], STARTUP_S)
        for k, data in enumerate((b'', b'\xff\xd8 not a jpeg', good), 1):
            pub.publish(CompressedImage(format='jpeg', data=data))
            spin_until(node, lambda: len(diags) >= k, [calib], 60)  # one image at a time: in order
        alive = calib.poll() is None
    finally:
        out = stop(calib)
        node.destroy_node()
        rclpy.shutdown()
    assert alive, f'calib died on bad input:\n{out}'
    assert 'empty compressed image' in out and 'corrupt compressed image' in out, out
    # one status per image: the bad ones reported as errors, the good one after them still processed
    statuses = [d.status[0] for d in diags]
    assert len(statuses) == 3, statuses
    assert [s.level for s in statuses[:2]] == [DiagnosticStatus.ERROR] * 2
    assert all(s.message.startswith(f'{CalibStatus.BAD_INPUT}: ') for s in statuses[:2]), statuses
    last = CalibStatus.from_name(dict((kv.key, kv.value) for kv in statuses[2].values)['status'])
    assert last is not CalibStatus.BAD_INPUT
