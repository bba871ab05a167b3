"""Message fields <-> core types, for ANY implementation of the ROS message types: rclpy's generated classes
(``matrix_ros.conversions``) and the ``rosbags`` type store (``matrix_core.bags.messages``) alike.

Readers take a message object and read its standard field names (duck typing: no message class is imported
here, the core stays free of ROS). Writers return the fields as a dict of plain Python / numpy values; the
caller builds its own message class from them (``CameraInfo(**fields)``). Every reader that can fail raises
:class:`ConversionError` with a one-line reason.

Conventions (docs/conventions.md):
    - ``sensor_msgs/CameraInfo``: ``k``, ``d`` the intrinsics and distortion, ``r`` identity and
      ``p = K [R | t]`` mapping homogeneous WORLD points to pixels (it carries the extrinsics).
    - ``sensor_msgs/Image``: bgr8 (written), bgr8 / rgb8 / mono8 / bgra8 / rgba8 (read) -> (H, W, 3) BGR uint8.
    - ``matrix_msgs/HomographyStamped``: the message form of
      :class:`~matrix_core.register.registration.Registration` (``h_cur_to_ref`` = ``ref_H_img``,
      ``h_img_to_ground`` = ``ground_H_img``, row-major, all zeros unless ``status`` is ``OK``; ``status`` the
      :class:`~matrix_core.register.registration.RegistrationStatus` value, ``reason`` its message).
    - stamps: ``builtin_interfaces/Time`` <-> float seconds (exact to the nanosecond).
"""

import cv2
import numpy as np

from matrix_core.encoded_images import CorruptImage, decode_image
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.quaternion import matrix_from_quaternion, quaternion_from_matrix
from matrix_core.register.registration import Registration, RegistrationError, RegistrationStatus, check_homography


class ConversionError(ValueError):
    """A message cannot be turned into the core type (bad encoding, size, NaN, corrupt data)."""


# --- time ---------------------------------------------------------------------------------------------
def stamp_fields(seconds: float) -> dict:
    """Seconds -> ``{'sec', 'nanosec'}`` of a builtin_interfaces/Time (exact to the nanosecond)."""
    ns = int(round(seconds * 1e9))
    return {'sec': ns // 1_000_000_000, 'nanosec': ns % 1_000_000_000}


def stamp_seconds(stamp) -> float:
    """builtin_interfaces/Time -> seconds."""
    return int(stamp.sec) + int(stamp.nanosec) * 1e-9


def stamp_ns(msg_header) -> int:
    """A std_msgs/Header's stamp -> integer nanoseconds (exact)."""
    return int(msg_header.stamp.sec) * 1_000_000_000 + int(msg_header.stamp.nanosec)


# --- images -------------------------------------------------------------------------------------------
_CHANNELS = {'bgr8': 3, 'rgb8': 3, 'mono8': 1, 'bgra8': 4, 'rgba8': 4}
_TO_BGR = {
    'rgb8': cv2.COLOR_RGB2BGR,
    'mono8': cv2.COLOR_GRAY2BGR,
    'bgra8': cv2.COLOR_BGRA2BGR,
    'rgba8': cv2.COLOR_RGBA2BGR,
}
_REDUCED = {
    1: cv2.IMREAD_COLOR,
    2: cv2.IMREAD_REDUCED_COLOR_2,
    4: cv2.IMREAD_REDUCED_COLOR_4,
    8: cv2.IMREAD_REDUCED_COLOR_8,
}


def _bytes(data) -> np.ndarray:
    """A message's uint8[] field (bytes, array.array, list or numpy) as a flat uint8 array."""
    if isinstance(data, np.ndarray):
        return data.astype(np.uint8, copy=False).reshape(-1)
    return np.frombuffer(bytes(data), dtype=np.uint8)


def image_fields(image: np.ndarray) -> dict:
    """(H, W, 3) BGR or (H, W) grey uint8 -> sensor_msgs/Image fields (bgr8 / mono8; ``data`` as bytes)."""
    if image.dtype != np.uint8 or image.ndim not in (2, 3) or (image.ndim == 3 and image.shape[2] != 3):
        raise ConversionError(f'expected uint8 (H, W) or (H, W, 3) image, got {image.dtype} {image.shape}')
    h, w = image.shape[:2]
    channels = 3 if image.ndim == 3 else 1
    return {
        'height': h,
        'width': w,
        'encoding': 'bgr8' if channels == 3 else 'mono8',
        'is_bigendian': 0,
        'step': w * channels,
        'data': np.ascontiguousarray(image).tobytes(),
    }


def is_jpeg(msg) -> bool:
    """Whether a sensor_msgs/CompressedImage holds a JPEG (by its format or its magic bytes)."""
    fmt = msg.format.lower()
    return 'jpeg' in fmt or 'jpg' in fmt or bytes(_bytes(msg.data[:2])) == b'\xff\xd8'


def compressed_fields(image: np.ndarray, fmt: str = 'jpeg', quality: int = 95) -> dict:
    """(H, W, 3) BGR uint8 -> sensor_msgs/CompressedImage fields (``format``, ``data`` as bytes)."""
    ext, params = ('.jpg', [cv2.IMWRITE_JPEG_QUALITY, quality]) if fmt == 'jpeg' else ('.png', [])
    ok, buf = cv2.imencode(ext, image, params)
    if not ok:
        raise ConversionError(f'cannot encode image as {fmt}')
    return {'format': fmt, 'data': buf.tobytes()}


def _decode_compressed(msg, data: np.ndarray, flags: int) -> np.ndarray:
    """A CompressedImage's ``data`` decoded with ``flags``; :class:`ConversionError` when it is cut short or
    corrupt (``encoded_images``: libjpeg alone decodes half a JPEG into a valid-looking image)."""
    try:
        return decode_image(data, flags)
    except CorruptImage as exc:
        raise ConversionError(f'corrupt compressed image ({msg.format!r}, {len(data)} bytes): {exc}') from exc


def image_from_msg(msg, reduction: int = 1) -> np.ndarray:
    """sensor_msgs/Image (bgr8, rgb8, mono8, bgra8, rgba8) or CompressedImage (jpeg/png) -> (H, W, 3) BGR
    uint8. A JPEG with ``reduction`` 2, 4 or 8 is decoded directly at that fraction of its size
    (ceil(W / r) x ceil(H / r)); raw images ignore ``reduction``."""
    if reduction not in _REDUCED:
        raise ValueError(f'reduction must be 1, 2, 4 or 8, got {reduction}')
    if hasattr(msg, 'format'):
        data = _bytes(msg.data)
        if len(data) == 0:
            raise ConversionError('empty compressed image')
        return _decode_compressed(msg, data, _REDUCED[reduction] if is_jpeg(msg) else cv2.IMREAD_COLOR)
    channels = _CHANNELS.get(msg.encoding)
    if channels is None:
        raise ConversionError(f'unsupported image encoding {msg.encoding!r} (supported: {sorted(_CHANNELS)})')
    if msg.height == 0 or msg.width == 0:
        raise ConversionError('empty image (0 x 0)')
    data, row = _bytes(msg.data), msg.width * channels
    if msg.step < row or len(data) < msg.step * msg.height:
        raise ConversionError(
            f'image data too short: {len(data)} bytes for {msg.width}x{msg.height} {msg.encoding} with step {msg.step}'
        )
    img = data[: msg.step * msg.height].reshape(msg.height, msg.step)[:, :row].reshape(msg.height, msg.width, channels)
    if msg.encoding == 'bgr8':
        return img.copy()
    return cv2.cvtColor(img if channels > 1 else img[:, :, 0], _TO_BGR[msg.encoding])


def gray_image_from_msg(msg) -> np.ndarray:
    """sensor_msgs/Image or CompressedImage -> (H, W) grey uint8, full size. A JPEG is decoded straight to
    grey (libjpeg then skips the colour upsampling and conversion: the cheapest full-size decode), for
    consumers that use grey only (calib, register; ``matrix_ros.drone_link``)."""
    if hasattr(msg, 'format') and len(msg.data) and is_jpeg(msg):
        return _decode_compressed(msg, _bytes(msg.data), cv2.IMREAD_GRAYSCALE)
    return cv2.cvtColor(image_from_msg(msg), cv2.COLOR_BGR2GRAY)


# --- cameras ------------------------------------------------------------------------------------------
def camera_info_fields(camera: Camera) -> dict:
    """:class:`Camera` -> sensor_msgs/CameraInfo fields with ``p = K [R | t]`` (world -> pixels)."""
    return {
        'width': int(camera.width),
        'height': int(camera.height),
        'distortion_model': 'plumb_bob',
        'd': [float(v) for v in camera.dist],
        'k': [float(v) for v in camera.K.reshape(-1)],
        'r': [float(v) for v in np.eye(3).reshape(-1)],
        'p': [float(v) for v in camera.P.reshape(-1)],
    }


def camera_from_camera_info(msg) -> Camera:
    """CameraInfo with ``p = K [R | t]`` -> :class:`Camera`; :class:`ConversionError` when it is not valid."""
    try:
        return Camera.from_projection(
            np.asarray(msg.k, dtype=np.float64),
            np.asarray(msg.p, dtype=np.float64),
            int(msg.width),
            int(msg.height),
            list(msg.d),
        )
    except ValueError as exc:
        raise ConversionError(f'invalid CameraInfo: {exc}') from exc


def pose_values(world_T_cam: np.ndarray) -> tuple:
    """(4, 4) pose -> ((x, y, z) position, (x, y, z, w) quaternion) for geometry_msgs/Pose."""
    x, y, z, w = quaternion_from_matrix(world_T_cam[:3, :3])
    return tuple(float(v) for v in world_T_cam[:3, 3]), (float(x), float(y), float(z), float(w))


def pose_matrix_from_msg(pose) -> np.ndarray:
    """geometry_msgs/Pose -> (4, 4) transform (``world_T_cam`` for a camera pose)."""
    q, p = pose.orientation, pose.position
    return pose_matrix(matrix_from_quaternion([q.x, q.y, q.z, q.w]), [p.x, p.y, p.z])


# --- registrations ------------------------------------------------------------------------------------
def _flat(H) -> list:
    return [0.0] * 9 if H is None else [float(v) for v in np.asarray(H, dtype=np.float64).reshape(-1)]


def registration_fields(registration: Registration) -> dict:
    """:class:`Registration` -> matrix_msgs/HomographyStamped fields (no header)."""
    r = registration
    error = float(r.inlier_error_px) if r.inlier_error_px is not None and np.isfinite(r.inlier_error_px) else 0.0
    return {
        'h_cur_to_ref': _flat(r.ref_H_img if r.ok else None),
        'h_img_to_ground': _flat(r.ground_H_img if r.ok else None),
        'confidence': float(r.confidence),
        'matches': int(r.matches),
        'inliers': int(r.inliers),
        'inlier_error_px': error,
        'status': int(r.status),
        'reason': r.message,
        'reference_id': r.reference_id,
        'backend': r.backend,
    }


def registration_from_msg(msg) -> Registration:
    """matrix_msgs/HomographyStamped -> :class:`Registration`. A message that says ``OK`` but whose
    ``h_img_to_ground`` breaks the validity rule, or whose status is no known value, comes back with status
    ``UNUSABLE`` saying why: consumers never see NaN or zero matrices."""
    values = {
        'confidence': float(msg.confidence),
        'matches': int(msg.matches),
        'inliers': int(msg.inliers),
        'inlier_error_px': float(msg.inlier_error_px),
        'reference_id': msg.reference_id,
        'backend': msg.backend,
    }
    try:
        status = RegistrationStatus(msg.status)
    except ValueError:
        return Registration(RegistrationStatus.UNUSABLE, message=f'unknown status {msg.status!r}', **values)
    if status != RegistrationStatus.OK:
        return Registration(status, message=msg.reason, **values)
    try:
        ground = check_homography(msg.h_img_to_ground, 'h_img_to_ground')
    except RegistrationError as exc:
        return Registration(RegistrationStatus.UNUSABLE, message=str(exc), **values)
    try:  # only the ground homography is the contract; a producer may leave the pixel one out (zeros)
        ref = check_homography(msg.h_cur_to_ref, 'h_cur_to_ref')
    except RegistrationError:
        ref = None
    return Registration(status, ref, ground, message=msg.reason, **values)
