"""The real ``register`` node in its own process registers real MATRIX images received over DDS.

Two more processes take part: the installed ``dataset_player`` publishes frames 0000-0002 of two drones
(a corner and a side drone, so the node handles several drones), and this test process listens to the
homographies, checks them against the ground truth from the stored calibrations, then sends a corrupt
image and checks that the node reports it and keeps running. Last, the replay starts over (frame 0 again at
its first stamp, time going back): the drone starts afresh from its reference and registers it.
"""

import time

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import Image
from std_msgs.msg import Header

from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.homography import apply_homography
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.ground_mask import visible_ground_grid
from matrix_core.register.settings import MATRIX_BLOCK
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import image_to_msg, seconds_to_stamp
from ros_helpers import spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]

VIEWS = ('D3', 'D6')
FRAMES = 3


def test_register_node_over_dds(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    views = '[' + ','.join(VIEWS) + ']'
    register = start_node(
        node_executable('matrix_register', 'register'), f'views:={views}', f'reference_dataset:={matrix_sample}'
    )
    rclpy.init()
    got = {v: [] for v in VIEWS}
    diags = []
    node = Node('register_test_listener')
    player = None
    try:
        homographies = [
            node.create_subscription(HomographyStamped, f'/{v}/homography', lambda m, v=v: got[v].append(m), 10)
            for v in VIEWS
        ]
        node.create_subscription(DiagnosticArray, '/diagnostics', diags.append, 10)
        # Start the images only once the register node is up and this listener is connected to it.
        wait_matched(node, homographies, [register], 120.0)
        player = start_node(
            node_executable('matrix_ros', 'dataset_player'),
            f'dataset:={matrix_sample}',
            f'views:={views}',
            f'max_frames:={FRAMES}',
            'rate:=2.0',
            'wait_for_subscribers:=1',
        )
        spin_until(node, lambda: all(len(m) >= FRAMES for m in got.values()), [register, player], 120.0)

        # Bad input: an image whose data is too short. The node must say so and keep running.
        bad_pub = node.create_publisher(Image, f'/{VIEWS[0]}/image_raw', 10)
        bad = Image(height=1080, width=1920, encoding='bgr8', step=5760)
        bad.data = bytes(100)
        bad.header.stamp.sec = 99

        def bad_reported():
            return any(s.level == DiagnosticStatus.ERROR and 'bad_input' in s.message for d in diags for s in d.status)

        deadline = time.monotonic() + 30.0  # sent again each second: the new publisher may not be matched yet
        while time.monotonic() < deadline and not bad_reported() and register.poll() is None:
            bad_pub.publish(bad)
            spin_until(node, bad_reported, [register], 1.0)
        alive = register.poll() is None
        # The replay starts over: the first frame again at its first stamp, long after the last one.
        count = len(got[VIEWS[0]])
        bad_pub.publish(
            image_to_msg(
                dataset.load_image(VIEWS[0], dataset.frames[0]), Header(stamp=seconds_to_stamp(1.0), frame_id='world')
            )
        )
        spin_until(node, lambda: len(got[VIEWS[0]]) > count, [register], 60.0)
        restarted = got[VIEWS[0]][count:]
    finally:
        node.destroy_node()
        rclpy.shutdown()
        player_out = stop(player) if player is not None else '(not started)'
        register_out = stop(register)
    log = f'register said:\n{register_out}\nplayer said:\n{player_out}'
    assert alive, f'register node died on a corrupt image; {log}'
    assert bad_reported(), f'no diagnostics error for the corrupt image; {log}'
    assert 'too short' in register_out, log
    assert restarted and stamp_seconds(restarted[0].header.stamp) == 1.0, log
    assert restarted[0].status == HomographyStamped.OK and restarted[0].reference_id == f'{VIEWS[0]}/reference', log
    assert f'{VIEWS[0]}: t=1.000 s: time went back, starting this drone afresh' in register_out, log
    failed = [m for m in got[VIEWS[0]] if m.header.stamp.sec == 99]  # downstream learns of it too
    assert failed and failed[0].status == HomographyStamped.BAD_INPUT and not any(failed[0].h_img_to_ground), log
    assert 'too short' in failed[0].reason, failed[0]

    for view in VIEWS:
        msgs = got[view]
        assert len(msgs) >= FRAMES, f'{view}: {len(msgs)} homographies; {log}'
        ref = dataset.reference_camera(view)
        for msg in msgs[:FRAMES]:
            index = round((stamp_seconds(msg.header.stamp) - 1.0) / 0.5)
            frame = dataset.frames[index]
            cur = dataset.camera(view, frame)
            assert msg.status == HomographyStamped.OK, f'{view} frame {frame}: {msg.status} {msg.reason}'
            assert msg.backend == 'sift' and msg.reference_id == f'{view}/reference'
            assert msg.inliers >= 15 and 0.0 < msg.confidence <= 1.0
            assert msg.confidence == pytest.approx(msg.inliers / msg.matches)
            H = np.array(msg.h_cur_to_ref).reshape(3, 3)
            error = homography_error_px(H, cur, ref, dataset.area, MATRIX_BLOCK)
            assert error < 1.5, f'{view} frame {frame}: {error:.2f} px from the ground truth'
            # The image-to-ground homography lands image points on their true world position.
            world = visible_ground_grid(cur, dataset.area, 1.0, MATRIX_BLOCK)
            est = apply_homography(np.array(msg.h_img_to_ground).reshape(3, 3), cur.ground_to_img(world))
            assert np.median(np.linalg.norm(est - world, axis=1)) < 0.1  # metres
