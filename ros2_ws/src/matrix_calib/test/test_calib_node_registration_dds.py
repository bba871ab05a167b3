"""The installed ``calib`` node with ``use_registration``, in its own process over DDS: this test publishes
real MATRIX images of drone D5 and registrations of the same stamps (ground truth, a failed one, a missing
one, a NaN one) and checks from calib's diagnostics which frames the registration guided, and that every
frame was still calibrated. Then the replay starts over (time goes back): the first frame again is calibrated
afresh, not refused as late."""

import numpy as np
import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from matrix_core.calib.status import CalibStatus
from matrix_core.datasets import MatrixDataset
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import image_to_compressed, seconds_to_stamp
from matrix_ros.qos import qos_by_name
from ros_helpers import spin_for, spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]
# What each frame's registration is, and how calib's diagnostics must say the frame was guided.
PLAN = [
    ('truth', 'registration'),
    ('failed', 'homography ('),
    ('none', 'homography ('),
    ('nan', 'registration homography unusable; homography ('),
    ('truth', 'registration'),
]


def _registration(header, dataset, frame, kind) -> HomographyStamped:
    msg = HomographyStamped(header=header, status=HomographyStamped.OK, confidence=0.9)
    H = np.linalg.inv(dataset.camera('D5', frame).img_H_ground())  # image pixels -> ground metres
    msg.h_img_to_ground = (np.full(9, np.nan) if kind == 'nan' else (H / H[2, 2]).ravel()).tolist()
    if kind == 'failed':
        msg.status, msg.reason, msg.h_img_to_ground = HomographyStamped.FAILED, 'test', [0.0] * 9
    return msg


def test_calib_follows_the_registration_and_copes_without_it(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    rclpy.init()
    node = Node('calib_registration_test')
    images = node.create_publisher(CompressedImage, '/D5/image/compressed', qos_by_name('reliable'))
    diags = {}
    diag_sub = node.create_subscription(
        DiagnosticArray,
        '/diagnostics',
        lambda m: diags.update({round(stamp_seconds(m.header.stamp), 3): s for s in m.status if s.name == 'calib/D5'}),
        50,
    )
    calib = start_node(
        node_executable('matrix_calib', 'calib'),
        'views:=[D5]',
        'compressed:=true',
        f'prior_dataset:={matrix_sample}',
        'qos:=reliable',
        'use_registration:=true',
        'registration_wait_s:=1.0',
        'restart_gap_s:=1.0',
    )
    try:
        assert spin_until(node, lambda: node.count_subscribers('/D5/homography') == 1, [calib], 120)
        # What is tested: for 2 s without a registration publisher, calib subscribes no images.
        spin_for(node, 2.0)
        unconnected = images.get_subscription_count()  # no registration publisher yet: no image subscription
        registrations = node.create_publisher(HomographyStamped, '/D5/homography', 10)
        # calib subscribes the images once its registration subscription matched this publisher; this
        # publisher's side of that match is waited for too, so that no registration is lost.
        wait_matched(node, [images, registrations, diag_sub], [calib], 60)
        for k, (kind, _) in enumerate(PLAN):
            frame, stamp = dataset.frames[k], 1.0 + 0.5 * k
            header = Header(stamp=seconds_to_stamp(stamp), frame_id='D5/camera_optical')
            images.publish(image_to_compressed(dataset.load_image('D5', frame), header))
            if kind != 'none':
                registrations.publish(_registration(header, dataset, frame, kind))
            assert spin_until(node, lambda: round(stamp, 3) in diags, [calib], 60), (stamp, kind)
        first = diags.pop(1.0)
        header = Header(stamp=seconds_to_stamp(1.0), frame_id='D5/camera_optical')  # the replay starts over
        images.publish(image_to_compressed(dataset.load_image('D5', dataset.frames[0]), header))
        registrations.publish(_registration(header, dataset, dataset.frames[0], 'truth'))
        assert spin_until(node, lambda: 1.0 in diags, [calib], 60), 'the restarted replay was refused'
    finally:
        out = stop(calib)
        node.destroy_node()
        rclpy.shutdown()
    assert unconnected == 0
    again = {kv.key: kv.value for kv in diags.pop(1.0).values}
    assert (
        CalibStatus.from_name(again['status']) is CalibStatus.OK
        and again['guide'] == 'time went back, started afresh; registration'
    ), again
    diags[1.0] = first
    for k, (kind, guide) in enumerate(PLAN):
        values = {kv.key: kv.value for kv in diags[round(1.0 + 0.5 * k, 3)].values}
        assert CalibStatus.from_name(values['status']) is CalibStatus.OK and values['guide'].startswith(guide), (
            kind,
            values,
        )
        assert values['tracked'] == str(guide == 'registration'), (kind, values)
    assert 'registration failed: test; calibrated from the image motion' in out, out
    assert 'no registration of t=2.000 s within 1.0 s: calibrated from the image motion' in out, out
