"""The standard-type twins of the outputs without DDS: tracks, detections and image boxes as vision_msgs, a
camera pose and the area as tf2 transforms; each through the serialisation a subscriber sees."""

import math
from types import SimpleNamespace

import numpy as np
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage
from vision_msgs.msg import Detection2DArray, Detection3DArray

from matrix_core import topics
from matrix_core.datasets import MatrixDataset
from matrix_core.fusion.image_boxes import ImageBox
from matrix_core.geometry.quaternion import matrix_from_quaternion
from matrix_core.tracking.track import BevDetections
from matrix_ros import vision_messages as vm
from matrix_ros.conversions import camera_to_pose


def _round_trip(msg, cls):
    return deserialize_message(serialize_message(msg), cls)


def _header(sec=7):
    header = Header(frame_id=topics.WORLD_FRAME)
    header.stamp.sec = sec
    return header


def test_tracks_as_detection_3d_array():
    tracks = [
        SimpleNamespace(track_id=12, score=0.8, xy=np.array([3.25, -7.5]), velocity=np.array([0.0, 1.0])),
        SimpleNamespace(track_id=4, score=0.6, xy=np.array([10.0, -20.0]), velocity=np.array([0.05, 0.0])),
    ]
    msg = _round_trip(vm.tracks_3d_msg(_header(), tracks, size=(0.6, 1.7)), Detection3DArray)
    assert msg.header.frame_id == 'world' and msg.header.stamp.sec == 7
    assert [d.id for d in msg.detections] == ['12', '4']
    first, second = msg.detections
    c = first.bbox.center
    assert (c.position.x, c.position.y, c.position.z) == (3.25, -7.5, 0.85)
    assert (first.bbox.size.x, first.bbox.size.y, first.bbox.size.z) == (0.6, 0.6, 1.7)
    hypothesis = first.results[0]
    assert hypothesis.hypothesis.class_id == topics.PERSON_CLASS_ID and math.isclose(hypothesis.hypothesis.score, 0.8)
    assert hypothesis.pose.pose.position.x == 3.25
    # walking along +y: the box turns 90 degrees; nearly standing: no direction
    yaw = 2 * math.atan2(c.orientation.z, c.orientation.w)
    assert math.isclose(yaw, math.pi / 2, abs_tol=1e-12)
    assert second.bbox.center.orientation.w == 1.0 and second.bbox.center.orientation.z == 0.0


def test_detections_have_no_id_and_move_against_their_offset():
    dets = BevDetections(xy=[[1.0, -2.0]], scores=[0.9], offsets=[[0.5, 0.0]])  # came from +x: moves to -x
    msg = _round_trip(vm.detections_3d_msg(_header(), dets, frame_interval_s=0.5), Detection3DArray)
    (d,) = msg.detections
    assert d.id == '' and d.bbox.center.position.x == 1.0 and d.bbox.center.position.y == -2.0
    yaw = 2 * math.atan2(d.bbox.center.orientation.z, d.bbox.center.orientation.w)
    assert math.isclose(abs(yaw), math.pi, abs_tol=1e-12)
    none = vm.detections_3d_msg(_header(), BevDetections(xy=[[1.0, 1.0]], scores=[0.5]), 0.5)
    assert none.detections[0].bbox.center.orientation.w == 1.0  # no offsets: no direction


def test_image_boxes_as_vision_detection_2d_array():
    boxes = [ImageBox(track_id=5, score=0.7, box=np.array([100.0, 200.0, 150.0, 320.0]), distance_m=12.0)]
    header = Header(frame_id=topics.optical_frame('D3'))
    msg = _round_trip(vm.detections_2d_msg(header, boxes), Detection2DArray)
    (d,) = msg.detections
    assert msg.header.frame_id == 'D3/camera_optical' and d.id == '5'
    assert (d.bbox.center.position.x, d.bbox.center.position.y, d.bbox.size_x, d.bbox.size_y) == (125, 260, 50, 120)
    assert d.results[0].hypothesis.class_id == 'person' and math.isclose(d.results[0].hypothesis.score, 0.7)


def test_camera_pose_as_tf_maps_the_optical_frame_to_the_world(matrix_sample):
    cam = MatrixDataset(matrix_sample).camera('D2', 0)
    pose = camera_to_pose(cam, _header())
    msg = _round_trip(vm.tf_msg(vm.pose_transform(pose, topics.optical_frame('D2'))), TFMessage)
    (t,) = msg.transforms
    assert t.header.frame_id == 'world' and t.child_frame_id == 'D2/camera_optical' and t.header.stamp.sec == 7
    r, p = t.transform.rotation, t.transform.translation
    R = matrix_from_quaternion([r.x, r.y, r.z, r.w])
    # parent_T_child: the camera centre is the translation; the optical z axis (view direction) in the world
    np.testing.assert_allclose([p.x, p.y, p.z], cam.center, atol=1e-9)
    np.testing.assert_allclose(R, cam.world_T_cam[:3, :3], atol=1e-9)


def test_area_frame_sits_at_the_area_corner():
    t = vm.area_transform('world', (0.0, -30.0, 30.0, 0.0))
    assert (t.header.frame_id, t.child_frame_id) == ('world', topics.AREA_FRAME)
    assert (t.transform.translation.x, t.transform.translation.y, t.transform.translation.z) == (0.0, -30.0, 0.0)
    assert t.transform.rotation.w == 1.0
