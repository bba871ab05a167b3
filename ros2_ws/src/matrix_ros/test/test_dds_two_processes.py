"""Two separate processes exchange real MATRIX images and CameraInfo over DDS with rclpy.

The publisher is the installed ``dataset_player`` executable in its own process; this test process
subscribes, and checks that every byte of the image and the calibration arrives unchanged.
"""

import numpy as np
import pytest
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image

from matrix_core.datasets import MatrixDataset
from matrix_core.message_fields import camera_from_camera_info, image_from_msg, stamp_seconds
from ros_helpers import spin_until, start_node, stop

pytestmark = pytest.mark.ros


def _collect(topics_types, until, process, timeout_s=60.0):
    """Subscribe to (topic, type) pairs; spin until ``until(received)``, the timeout, or ``process`` exits."""
    received = {topic: [] for topic, _ in topics_types}
    node = Node('dds_test_listener')
    for topic, msg_type in topics_types:
        node.create_subscription(msg_type, topic, lambda m, t=topic: received[t].append(m), 10)
    spin_until(node, lambda: until(received), [process], timeout_s)
    node.destroy_node()
    return received


def test_image_and_camera_info_cross_process(matrix_sample, node_executable):
    dataset = MatrixDataset(matrix_sample)
    rclpy.init()
    player = start_node(
        node_executable('matrix_ros', 'dataset_player'),
        f'dataset:={matrix_sample}',
        'views:=[D3]',
        'max_frames:=2',
        'rate:=4.0',
        'wait_for_subscribers:=1',
    )
    try:
        topics = [('/D3/image_raw', Image), ('/D3/ground_truth/camera_info', CameraInfo)]
        got = _collect(topics, lambda r: all(len(v) >= 2 for v in r.values()), player)
    finally:
        out = stop(player)
        rclpy.shutdown()
    assert len(got['/D3/image_raw']) >= 2, f'no images over DDS; player said:\n{out}'
    assert len(got['/D3/ground_truth/camera_info']) >= 2, f'no CameraInfo over DDS; player said:\n{out}'

    for index, (img_msg, info_msg) in enumerate(zip(got['/D3/image_raw'], got['/D3/ground_truth/camera_info'])):
        frame = dataset.frames[index]
        assert img_msg.header.stamp == info_msg.header.stamp
        assert stamp_seconds(img_msg.header.stamp) == pytest.approx(1.0 + 0.5 * index)
        assert (img_msg.width, img_msg.height, img_msg.encoding) == (1920, 1080, 'bgr8')
        np.testing.assert_array_equal(image_from_msg(img_msg), dataset.load_image('D3', frame))
        sent = dataset.camera('D3', frame)
        cam = camera_from_camera_info(info_msg)
        np.testing.assert_allclose(cam.K, sent.K, atol=1e-9)
        np.testing.assert_allclose(cam.cam_T_world, sent.cam_T_world, atol=1e-9)
        np.testing.assert_allclose(cam.dist, sent.dist, atol=1e-15)
