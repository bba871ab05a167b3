"""Message conversions on real MATRIX data, including the bad inputs nodes must survive."""

import numpy as np
import pytest
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core.datasets import MatrixDataset
from matrix_core.message_fields import ConversionError, camera_from_camera_info, image_from_msg, stamp_seconds
from matrix_ros.conversions import (
    camera_to_camera_info,
    camera_to_pose,
    image_to_compressed,
    image_to_msg,
    pose_to_world_T_cam,
    seconds_to_stamp,
)


@pytest.fixture(scope='module')
def ds(matrix_sample):
    return MatrixDataset(matrix_sample)


def test_image_roundtrip_and_encodings(ds):
    img = ds.load_image('D2', 1)
    msg = image_to_msg(img)
    np.testing.assert_array_equal(image_from_msg(msg), img)
    rgb = Image(
        height=msg.height,
        width=msg.width,
        encoding='rgb8',
        step=msg.step,
        data=np.ascontiguousarray(img[:, :, ::-1]).tobytes(),
    )
    np.testing.assert_array_equal(image_from_msg(rgb), img)
    grey = image_to_msg(img[:, :, 1])
    assert grey.encoding == 'mono8'
    np.testing.assert_array_equal(image_from_msg(grey)[:, :, 0], img[:, :, 1])


@pytest.mark.parametrize(
    'bad, reason',
    [
        (Image(height=4, width=4, encoding='16UC1', step=8, data=bytes(32)), 'unsupported image encoding'),
        (Image(height=0, width=0, encoding='bgr8'), 'empty image'),
        (Image(height=4, width=4, encoding='bgr8', step=12, data=bytes(10)), 'too short'),
    ],
)
def test_bad_images_raise_clear_errors(bad, reason):
    with pytest.raises(ConversionError, match=reason):
        image_from_msg(bad)


def test_compressed(ds):
    img = ds.load_image('D1', 0)
    dec = image_from_msg(image_to_compressed(img, quality=98))
    assert dec.shape == img.shape and np.abs(dec.astype(int) - img).mean() < 3
    with pytest.raises(ConversionError, match='corrupt'):
        image_from_msg(CompressedImage(format='jpeg', data=b'\xff\xd8garbage'))
    with pytest.raises(ConversionError, match='empty'):
        image_from_msg(CompressedImage(format='jpeg'))


def test_camera_info_roundtrip_and_projection(ds):
    cam = ds.camera('D5', 3)
    msg = camera_to_camera_info(cam)
    P = np.array(msg.p).reshape(3, 4)
    person = ds.annotations(3)[0]
    X = np.r_[person.world_xy, 0.0, 1.0]
    uv = (P @ X)[:2] / (P @ X)[2]
    np.testing.assert_allclose(uv, cam.ground_to_img(person.world_xy)[0], atol=1e-6)
    back = camera_from_camera_info(msg)
    np.testing.assert_allclose(back.cam_T_world, cam.cam_T_world, atol=1e-9)
    assert (back.width, back.height) == (1920, 1080)


def test_camera_info_rejects_nan_and_non_rotation(ds):
    msg = camera_to_camera_info(ds.camera('D1', 0))
    nan = CameraInfo(k=msg.k, p=[float('nan')] * 12, width=1920, height=1080)
    with pytest.raises(ConversionError, match='NaN'):
        camera_from_camera_info(nan)
    scaled = CameraInfo(k=msg.k, p=[2.0 * v for v in msg.p], width=1920, height=1080)
    with pytest.raises(ConversionError, match='proper rotation'):
        camera_from_camera_info(scaled)


def test_pose_is_camera_in_world(ds):
    cam = ds.camera('D7', 2)
    msg = camera_to_pose(cam)
    np.testing.assert_allclose([msg.pose.position.x, msg.pose.position.y, msg.pose.position.z], cam.center, atol=1e-9)
    np.testing.assert_allclose(pose_to_world_T_cam(msg), cam.world_T_cam, atol=1e-9)


def test_stamps_are_exact():
    for t in (0.0, 1.5, 12345.000000001):
        assert stamp_seconds(seconds_to_stamp(t)) == pytest.approx(t, abs=1e-9)
