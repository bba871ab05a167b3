"""The fuse node's image outputs without DDS: each view's camera from CameraInfo or from a registration with
the scene's reference intrinsics, the boxes of the real annotated people, and the messages' round trip."""

from types import SimpleNamespace

import numpy as np
import pytest
from matrix_msgs.msg import Detection2DArray
from rclpy.serialization import deserialize_message, serialize_message
from std_msgs.msg import Header

from matrix_core import topics
from matrix_core.datasets import MatrixDataset
from matrix_core.fusion.image_boxes import ImageBoxSettings
from matrix_core.fusion.image_outputs import ViewCameras
from matrix_core.message_fields import image_from_msg
from matrix_core.register.registration import Registration
from matrix_ros import fusion_messages as out
from matrix_ros.conversions import camera_to_camera_info, registration_to_msg


@pytest.fixture(scope='module')
def ds(matrix_sample):
    return MatrixDataset(matrix_sample)


def test_camera_info_and_registration_give_the_same_boxes(ds, matrix_sample):
    cameras = ViewCameras.from_dataset(ImageBoxSettings(), matrix_sample, ['D2'])
    cam = ds.camera('D2', 1)
    people = ds.annotations(1)
    tracks = [SimpleNamespace(track_id=p.person_id, score=0.9, xy=p.world_xy, detection_xy=None) for p in people]
    geometry = {
        'info': camera_to_camera_info(cam),
        'registration': registration_to_msg(Registration.from_img_H_ground(cam.img_H_ground())),
    }
    from_info = cameras.frame_boxes({'D2': geometry['info']}, tracks)['D2']
    from_registration = cameras.frame_boxes({'D2': geometry['registration']}, tracks)['D2']
    assert [b.track_id for b in from_info] == [b.track_id for b in from_registration]
    np.testing.assert_allclose([b.box for b in from_info], [b.box for b in from_registration], atol=0.5)
    # the annotated people of D2 are found where they were annotated
    annotated = {p.person_id: p.boxes['D2'] for p in people if 'D2' in p.boxes}
    found = {b.track_id for b in from_info}
    assert len(found & set(annotated)) >= 0.9 * len(annotated)
    assert cameras.frame_boxes({'D2': None}, tracks) == {}  # no geometry, no boxes
    assert ViewCameras(ImageBoxSettings()).frame_boxes({'D2': geometry['registration']}, tracks) == {}  # no K
    failed = registration_to_msg(Registration.failed('too few inliers'))
    assert cameras.frame_boxes({'D2': failed}, tracks) == {}


def test_detections_2d_message_round_trip_and_overlay(ds, matrix_sample):
    cameras = ViewCameras.from_dataset(ImageBoxSettings(), matrix_sample, ['D1'])
    tracks = [
        SimpleNamespace(track_id=p.person_id, score=0.5, xy=np.zeros(2), detection_xy=p.world_xy)
        for p in ds.annotations(0)
    ]
    boxes = cameras.frame_boxes({'D1': camera_to_camera_info(ds.camera('D1', 0))}, tracks)['D1']
    header = Header(frame_id=topics.optical_frame('D1'))
    header.stamp.sec = 3
    msg = deserialize_message(serialize_message(out.detections_2d_msg(header, boxes)), Detection2DArray)
    assert msg.header.frame_id == 'D1/camera_optical' and msg.header.stamp.sec == 3
    assert [d.id for d in msg.detections] == [b.track_id for b in boxes]
    np.testing.assert_allclose([[d.x_min, d.y_min, d.x_max, d.y_max] for d in msg.detections], [b.box for b in boxes])
    assert [d.distance_m for d in msg.detections] == sorted(d.distance_m for d in msg.detections)
    assert all(d.score == 0.5 for d in msg.detections)
    overlay = out.overlay_msg(header, ds.load_image('D1', 0), boxes)
    assert overlay.format == 'jpeg' and image_from_msg(overlay).shape == (1080, 1920, 3)
