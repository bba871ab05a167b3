"""``rosbags`` message objects (Jazzy type store; no rclpy) <-> core types, for the messages a sequence bag
holds. The field conventions and checks are :mod:`matrix_core.message_fields`'s (shared with
``matrix_ros.conversions``); this module only builds rosbags' classes. Failures raise ``ValueError``
(``ConversionError`` is one).
"""

import numpy as np
from rosbags.typesys import Stores, get_typestore

from matrix_core import message_fields as fields
from matrix_core import topics
from matrix_core.geometry.camera import Camera, pose_matrix

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
_T = TYPESTORE.types


def header(stamp_ns: int, frame_id: str):
    return _T[topics.HEADER_TYPE](
        stamp=_T['builtin_interfaces/msg/Time'](
            sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000)
        ),
        frame_id=frame_id,
    )


def image_msg(image: np.ndarray, hdr):
    """(H, W, 3) BGR uint8 -> sensor_msgs/Image bgr8."""
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f'expected (H, W, 3) uint8 BGR image, got {image.dtype} {image.shape}')
    f = fields.image_fields(image)
    return _T[topics.IMAGE_TYPE](header=hdr, **{**f, 'data': np.frombuffer(f['data'], np.uint8)})


def compressed_msg(image: np.ndarray, hdr, quality: int = 95):
    f = fields.compressed_fields(image, 'jpeg', quality)
    return _T[topics.COMPRESSED_TYPE](header=hdr, format=f['format'], data=np.frombuffer(f['data'], np.uint8))


def camera_info_msg(camera: Camera, hdr):
    """Camera -> CameraInfo with p = K [R | t] (world -> pixels)."""
    f = fields.camera_info_fields(camera)
    return _T[topics.CAMERA_INFO_TYPE](
        header=hdr,
        height=f['height'],
        width=f['width'],
        distortion_model=f['distortion_model'],
        **{k: np.asarray(f[k], dtype=np.float64) for k in ('d', 'k', 'r', 'p')},
        binning_x=0,
        binning_y=0,
        roi=_T['sensor_msgs/msg/RegionOfInterest'](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )


def _pose(T: np.ndarray):
    (px, py, pz), (x, y, z, w) = fields.pose_values(T)
    return _T['geometry_msgs/msg/Pose'](
        position=_T['geometry_msgs/msg/Point'](x=px, y=py, z=pz),
        orientation=_T['geometry_msgs/msg/Quaternion'](x=x, y=y, z=z, w=w),
    )


def pose_msg(camera: Camera, hdr):
    """Camera pose world_T_cam as geometry_msgs/PoseStamped."""
    return _T[topics.POSE_TYPE](header=hdr, pose=_pose(camera.world_T_cam))


pose_to_matrix = fields.pose_matrix_from_msg  # geometry_msgs/Pose -> (4, 4)


def pedestrians_msg(positions: dict, hdr):
    """person id -> (3,) metres as PoseArray (ordered by id) and the matching Int32MultiArray of ids."""
    ids = sorted(positions)
    poses = [_pose(pose_matrix(np.eye(3), np.asarray(positions[i], dtype=float))) for i in ids]
    layout = _T['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0)
    return (
        _T[topics.POSE_ARRAY_TYPE](header=hdr, poses=poses),
        _T[topics.IDS_TYPE](layout=layout, data=np.array(ids, dtype=np.int32)),
    )
