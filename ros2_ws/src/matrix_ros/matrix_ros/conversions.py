"""core types -> rclpy messages. The field conventions and every check live in
:mod:`matrix_core.message_fields` (shared with the rosbags side, ``matrix_core.bags.messages``), which also
reads messages back (``image_from_msg``, ``camera_from_camera_info``, ``registration_from_msg``,
``stamp_seconds``, ...: they take any message with the fields); this module only builds rclpy's message
classes. Every conversion that can fail raises :class:`matrix_core.message_fields.ConversionError` with a
one-line reason.
"""

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from matrix_msgs.msg import HomographyStamped
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core import message_fields as fields
from matrix_core.geometry.camera import Camera
from matrix_core.register.registration import Registration


def seconds_to_stamp(seconds: float) -> Time:
    """Seconds -> builtin_interfaces/Time (exact to the nanosecond)."""
    return Time(**fields.stamp_fields(seconds))


def _with_header(msg, header):
    if header is not None:
        msg.header = header
    return msg


def image_to_msg(image: np.ndarray, header=None) -> Image:
    """(H, W, 3) BGR or (H, W) grey uint8 array -> sensor_msgs/Image (bgr8 / mono8)."""
    return _with_header(Image(**fields.image_fields(image)), header)


def image_to_compressed(image: np.ndarray, header=None, fmt: str = 'jpeg', quality: int = 95) -> CompressedImage:
    """(H, W, 3) BGR uint8 -> sensor_msgs/CompressedImage."""
    return _with_header(CompressedImage(**fields.compressed_fields(image, fmt, quality)), header)


def camera_to_camera_info(camera: Camera, header=None) -> CameraInfo:
    """:class:`Camera` -> CameraInfo with ``p = K [R | t]`` (world -> pixels)."""
    return _with_header(CameraInfo(**fields.camera_info_fields(camera)), header)


def camera_to_pose(camera: Camera, header=None) -> PoseStamped:
    """Camera pose ``world_T_cam`` (optical frame) as PoseStamped in the world frame."""
    msg = _with_header(PoseStamped(), header)
    (msg.pose.position.x, msg.pose.position.y, msg.pose.position.z), q = fields.pose_values(camera.world_T_cam)
    msg.pose.orientation.x, msg.pose.orientation.y, msg.pose.orientation.z, msg.pose.orientation.w = q
    return msg


def pose_to_world_T_cam(msg: PoseStamped) -> np.ndarray:
    """PoseStamped -> (4, 4) ``world_T_cam``."""
    return fields.pose_matrix_from_msg(msg.pose)


def registration_to_msg(registration: Registration, header=None) -> HomographyStamped:
    """:class:`Registration` -> matrix_msgs/HomographyStamped (its message form)."""
    return _with_header(HomographyStamped(**fields.registration_fields(registration)), header)
