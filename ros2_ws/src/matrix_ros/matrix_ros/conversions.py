"""Conversions between core types (numpy images, :class:`~matrix_core.geometry.camera.Camera`) and
ROS messages. Every conversion that can fail raises :class:`ConversionError` with a one-line reason.

CameraInfo convention (documented in the README): ``k`` and ``d`` are the intrinsics and distortion,
``r`` is identity, and ``p = K [R | t]`` maps homogeneous WORLD points (metres, the frame named by
``world_frame``) to image pixels, i.e. it carries the camera's extrinsics. ``header.frame_id`` is the
camera's optical frame.
"""

import cv2
import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core.geometry.camera import Camera, pose_matrix


class ConversionError(ValueError):
    """A message cannot be turned into the core type (bad encoding, size, NaN, corrupt data)."""


_CHANNELS = {'bgr8': 3, 'rgb8': 3, 'mono8': 1, 'bgra8': 4, 'rgba8': 4}


def seconds_to_stamp(seconds: float) -> Time:
    """Seconds -> builtin_interfaces/Time (exact to the nanosecond)."""
    ns = int(round(seconds * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def stamp_to_seconds(stamp) -> float:
    """builtin_interfaces/Time -> seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def image_to_msg(image: np.ndarray, header=None) -> Image:
    """(H, W, 3) BGR or (H, W) grey uint8 array -> sensor_msgs/Image (bgr8 / mono8)."""
    if image.dtype != np.uint8 or image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ConversionError(f'expected uint8 (H, W) or (H, W, 3) image, got {image.dtype} {image.shape}')
    msg = Image()
    if header is not None:
        msg.header = header
    msg.height, msg.width = image.shape[:2]
    msg.encoding = 'bgr8' if image.ndim == 3 else 'mono8'
    msg.step = image.shape[1] * (3 if image.ndim == 3 else 1)
    msg.data = np.ascontiguousarray(image).tobytes()
    return msg


def msg_to_image(msg: Image) -> np.ndarray:
    """sensor_msgs/Image (bgr8, rgb8, mono8, bgra8, rgba8) -> (H, W, 3) BGR uint8."""
    channels = _CHANNELS.get(msg.encoding)
    if channels is None:
        raise ConversionError(f'unsupported image encoding {msg.encoding!r} (supported: {sorted(_CHANNELS)})')
    if msg.height == 0 or msg.width == 0:
        raise ConversionError('empty image (0 x 0)')
    row = msg.width * channels
    if msg.step < row or len(msg.data) < msg.step * msg.height:
        raise ConversionError(f'image data too short: {len(msg.data)} bytes for {msg.width}x{msg.height} '
                              f'{msg.encoding} with step {msg.step}')
    buf = np.frombuffer(bytes(msg.data), dtype=np.uint8)[:msg.step * msg.height]
    img = buf.reshape(msg.height, msg.step)[:, :row].reshape(msg.height, msg.width, channels)
    if msg.encoding == 'bgr8':
        return img.copy()
    code = {'rgb8': cv2.COLOR_RGB2BGR, 'mono8': cv2.COLOR_GRAY2BGR, 'bgra8': cv2.COLOR_BGRA2BGR,
            'rgba8': cv2.COLOR_RGBA2BGR}[msg.encoding]
    return cv2.cvtColor(img if channels > 1 else img[:, :, 0], code)


_REDUCED = {1: cv2.IMREAD_COLOR, 2: cv2.IMREAD_REDUCED_COLOR_2, 4: cv2.IMREAD_REDUCED_COLOR_4,
            8: cv2.IMREAD_REDUCED_COLOR_8}


def is_jpeg(msg: CompressedImage) -> bool:
    return 'jpeg' in msg.format.lower() or 'jpg' in msg.format.lower() or bytes(msg.data[:2]) == b'\xff\xd8'


def compressed_to_image(msg: CompressedImage, reduction: int = 1) -> np.ndarray:
    """sensor_msgs/CompressedImage (jpeg/png) -> (H, W, 3) BGR uint8; a JPEG with ``reduction`` 2, 4 or 8 is
    decoded directly at that fraction of its size (ceil(W / r) x ceil(H / r))."""
    if len(msg.data) == 0:
        raise ConversionError('empty compressed image')
    if reduction not in _REDUCED:
        raise ValueError(f'reduction must be 1, 2, 4 or 8, got {reduction}')
    flag = _REDUCED[reduction] if is_jpeg(msg) else cv2.IMREAD_COLOR
    img = cv2.imdecode(np.frombuffer(bytes(msg.data), dtype=np.uint8), flag)
    if img is None:
        raise ConversionError(f'corrupt compressed image ({msg.format!r}, {len(msg.data)} bytes)')
    return img


def image_to_compressed(image: np.ndarray, header=None, fmt: str = 'jpeg', quality: int = 95) -> CompressedImage:
    """(H, W, 3) BGR uint8 -> sensor_msgs/CompressedImage."""
    ext, params = ('.jpg', [cv2.IMWRITE_JPEG_QUALITY, quality]) if fmt == 'jpeg' else ('.png', [])
    ok, buf = cv2.imencode(ext, image, params)
    if not ok:
        raise ConversionError(f'cannot encode image as {fmt}')
    msg = CompressedImage()
    if header is not None:
        msg.header = header
    msg.format = fmt
    msg.data = buf.tobytes()
    return msg


def camera_to_camera_info(camera: Camera, header=None) -> CameraInfo:
    """:class:`Camera` -> CameraInfo with ``p = K [R | t]`` (world -> pixels), see the module docstring."""
    msg = CameraInfo()
    if header is not None:
        msg.header = header
    msg.width, msg.height = int(camera.width), int(camera.height)
    msg.distortion_model = 'plumb_bob'
    msg.d = [float(v) for v in camera.dist]
    msg.k = [float(v) for v in camera.K.reshape(-1)]
    msg.r = [float(v) for v in np.eye(3).reshape(-1)]
    msg.p = [float(v) for v in camera.P.reshape(-1)]
    return msg


def camera_info_to_camera(msg: CameraInfo) -> Camera:
    """CameraInfo with ``p = K [R | t]`` -> :class:`Camera`; raises :class:`ConversionError` if invalid."""
    K = np.array(msg.k, dtype=np.float64).reshape(3, 3)
    P = np.array(msg.p, dtype=np.float64).reshape(3, 4)
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(P))) or abs(np.linalg.det(K)) < 1e-9:
        raise ConversionError('CameraInfo has a NaN, infinite or singular K/P')
    Rt = np.linalg.solve(K, P)
    U, _, Vt = np.linalg.svd(Rt[:, :3])  # re-orthonormalise against float noise
    R = U @ Vt
    if np.linalg.det(R) < 0 or not np.allclose(R, Rt[:, :3], atol=1e-5):
        raise ConversionError('CameraInfo p is not K [R | t] with a proper rotation R')
    d = list(msg.d) + [0.0] * max(0, 5 - len(msg.d))
    try:
        return Camera(K, pose_matrix(R, Rt[:, 3]), int(msg.width), int(msg.height), np.array(d[:5]))
    except ValueError as exc:
        raise ConversionError(f'invalid CameraInfo: {exc}') from exc


def camera_to_pose(camera: Camera, header=None) -> PoseStamped:
    """Camera pose ``world_T_cam`` (optical frame) as PoseStamped in the world frame."""
    msg = PoseStamped()
    if header is not None:
        msg.header = header
    world_T_cam = camera.world_T_cam
    x, y, z, w = Rotation.from_matrix(world_T_cam[:3, :3]).as_quat()
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = (float(v) for v in world_T_cam[:3, 3])
    msg.pose.orientation.x, msg.pose.orientation.y = float(x), float(y)
    msg.pose.orientation.z, msg.pose.orientation.w = float(z), float(w)
    return msg


def pose_to_world_T_cam(msg: PoseStamped) -> np.ndarray:
    """PoseStamped -> (4, 4) ``world_T_cam``."""
    q = msg.pose.orientation
    p = msg.pose.position
    return pose_matrix(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), [p.x, p.y, p.z])
