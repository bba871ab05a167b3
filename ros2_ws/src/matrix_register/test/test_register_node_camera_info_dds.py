"""The real ``register`` node without a configured dataset takes its reference from a CameraInfo over DDS.

This test process publishes real MATRIX images of one drone and the CameraInfo (``p = K [R | t]``) of its
reference calibration: first an image that never gets a CameraInfo, then the reference image and only
AFTER it its CameraInfo (same stamp; the node must pair them by stamp, not take whatever came first),
then three frames. The homographies are checked against the ground truth from the stored calibrations.
"""

import numpy as np
import pytest
import rclpy
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

from matrix_core.datasets import MatrixDataset
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.settings import MATRIX_BLOCK
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import camera_to_camera_info, image_to_msg, seconds_to_stamp
from ros_helpers import spin_for, spin_until, start_node, stop, wait_matched

pytestmark = [pytest.mark.ros, pytest.mark.slow]

VIEW = 'D5'
ORPHAN_S, REFERENCE_S = 0.5, 1.0  # stamps: an image without CameraInfo, the reference image
FRAME_S = {2.0: 0, 2.5: 2, 3.0: 4}  # stamp -> frame of the sample


def test_reference_from_camera_info_over_dds(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    ref_cam = dataset.reference_camera(VIEW)
    register = start_node(node_executable('matrix_register', 'register'), f'views:=[{VIEW}]')
    rclpy.init()
    got = {}
    node = Node('register_camera_info_test')
    try:
        homographies = node.create_subscription(
            HomographyStamped, f'/{VIEW}/homography', lambda m: got.__setitem__(stamp_seconds(m.header.stamp), m), 10
        )
        image_pub = node.create_publisher(Image, f'/{VIEW}/image_raw', 10)
        info_pub = node.create_publisher(CameraInfo, f'/{VIEW}/camera_info', 10)
        wait_matched(node, [image_pub, info_pub, homographies], [register], 120.0)

        def header(seconds):
            return Header(stamp=seconds_to_stamp(seconds), frame_id=f'{VIEW}/camera_optical')

        # The order of arrival across the image and CameraInfo topics is what is tested, and the node answers
        # neither image before the reference's CameraInfo: nothing to wait for but time (1 s each).
        image_pub.publish(image_to_msg(dataset.load_image(VIEW, 1), header(ORPHAN_S)))
        spin_for(node, 1.0)
        reference = dataset.reference_image(VIEW)
        image_pub.publish(image_to_msg(reference, header(REFERENCE_S)))
        spin_for(node, 1.0)  # the reference image is held until its CameraInfo comes
        info_pub.publish(camera_to_camera_info(ref_cam, header(REFERENCE_S)))
        for seconds, frame in FRAME_S.items():
            image_pub.publish(image_to_msg(dataset.load_image(VIEW, frame), header(seconds)))
            spin_until(node, lambda: seconds in got, [register], 60.0)  # one frame at a time
        spin_until(node, lambda: len(got) >= 2 + len(FRAME_S), [register], 60.0)
        alive = register.poll() is None
    finally:
        node.destroy_node()
        rclpy.shutdown()
        out = stop(register)
    log = f'register said:\n{out}'
    assert alive, log
    assert sorted(got) == sorted([ORPHAN_S, REFERENCE_S, *FRAME_S]), f'homographies at {sorted(got)}; {log}'
    # The image without a CameraInfo is reported failed, with zero matrices, never used as the reference.
    orphan = got[ORPHAN_S]
    assert orphan.status == HomographyStamped.FAILED and 'before the reference' in orphan.reason, orphan
    assert not any(orphan.h_cur_to_ref)
    # The reference registers to itself.
    ref_msg = got[REFERENCE_S]
    assert ref_msg.status == HomographyStamped.OK, ref_msg
    np.testing.assert_allclose(np.array(ref_msg.h_cur_to_ref).reshape(3, 3), np.eye(3), atol=2e-3)
    for seconds, frame in FRAME_S.items():
        msg = got[seconds]
        assert msg.status == HomographyStamped.OK, f'frame {frame}: {msg.status} {msg.reason}'
        assert msg.reference_id == f'{VIEW}/frame/1.000000000'
        H = np.array(msg.h_cur_to_ref).reshape(3, 3)
        error = homography_error_px(H, dataset.camera(VIEW, frame), ref_cam, dataset.area, MATRIX_BLOCK)
        assert error < 1.5, f'frame {frame}: {error:.2f} px from the ground truth'
        # Ground homography = the CameraInfo's ground homography after H: lands pixels on the world.
        H_ground = np.array(msg.h_img_to_ground).reshape(3, 3)
        expected = ref_cam.ground_H_img() @ H
        np.testing.assert_allclose(H_ground / H_ground[2, 2], expected / expected[2, 2], rtol=1e-6, atol=1e-9)
