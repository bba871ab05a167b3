"""Conversions between core types and ``rosbags`` message objects (Jazzy type store; no rclpy).

Mirrors ``matrix_ros.conversions`` for the messages a sequence bag holds. Failures raise ``ValueError``.
"""

import cv2
import numpy as np
from rosbags.typesys import Stores, get_typestore
from scipy.spatial.transform import Rotation

from matrix_core.geometry.camera import Camera, pose_matrix

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
_T = TYPESTORE.types


def header(stamp_ns: int, frame_id: str):
    return _T['std_msgs/msg/Header'](stamp=_T['builtin_interfaces/msg/Time'](
        sec=int(stamp_ns // 1_000_000_000), nanosec=int(stamp_ns % 1_000_000_000)), frame_id=frame_id)


def stamp_ns(msg_header) -> int:
    return int(msg_header.stamp.sec) * 1_000_000_000 + int(msg_header.stamp.nanosec)


def image_msg(image: np.ndarray, hdr):
    """(H, W, 3) BGR uint8 -> sensor_msgs/Image bgr8."""
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f'expected (H, W, 3) uint8 BGR image, got {image.dtype} {image.shape}')
    h, w = image.shape[:2]
    return _T['sensor_msgs/msg/Image'](header=hdr, height=h, width=w, encoding='bgr8', is_bigendian=0,
                                       step=w * 3, data=np.ascontiguousarray(image).reshape(-1))


def compressed_msg(image: np.ndarray, hdr, quality: int = 95):
    ok, buf = cv2.imencode('.jpg', image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise ValueError('cannot JPEG-encode image')
    return _T['sensor_msgs/msg/CompressedImage'](header=hdr, format='jpeg', data=buf.reshape(-1))


def msg_to_image(msg) -> np.ndarray:
    """sensor_msgs/Image (bgr8, rgb8, mono8) or CompressedImage -> (H, W, 3) BGR uint8."""
    if hasattr(msg, 'format'):
        img = cv2.imdecode(np.asarray(msg.data, dtype=np.uint8), cv2.IMREAD_COLOR)
        if img is None:
            raise ValueError(f'corrupt compressed image ({msg.format!r})')
        return img
    ch = {'bgr8': 3, 'rgb8': 3, 'mono8': 1}.get(msg.encoding)
    if ch is None:
        raise ValueError(f'unsupported image encoding {msg.encoding!r}')
    data = np.asarray(msg.data, dtype=np.uint8)
    if msg.step < msg.width * ch or len(data) < msg.step * msg.height:
        raise ValueError('image data shorter than height * step')
    img = data[:msg.step * msg.height].reshape(msg.height, msg.step)[:, :msg.width * ch]
    img = img.reshape(msg.height, msg.width, ch)
    if msg.encoding == 'rgb8':
        return cv2.cvtColor(img, cv2.COLOR_RGB2BGR)
    return cv2.cvtColor(img[..., 0], cv2.COLOR_GRAY2BGR) if ch == 1 else img.copy()


def camera_info_msg(camera: Camera, hdr):
    """Camera -> CameraInfo with p = K [R | t] (world -> pixels)."""
    return _T['sensor_msgs/msg/CameraInfo'](
        header=hdr, height=int(camera.height), width=int(camera.width), distortion_model='plumb_bob',
        d=np.asarray(camera.dist, dtype=np.float64), k=camera.K.reshape(-1).astype(np.float64),
        r=np.eye(3).reshape(-1), p=camera.P.reshape(-1).astype(np.float64), binning_x=0, binning_y=0,
        roi=_T['sensor_msgs/msg/RegionOfInterest'](x_offset=0, y_offset=0, height=0, width=0,
                                                   do_rectify=False))


def camera_info_to_camera(msg) -> Camera:
    """CameraInfo (p = K [R | t]) -> Camera; ValueError when K/P are not finite or not of that form."""
    K = np.asarray(msg.k, dtype=np.float64).reshape(3, 3)
    P = np.asarray(msg.p, dtype=np.float64).reshape(3, 4)
    if not (np.isfinite(K).all() and np.isfinite(P).all()) or abs(np.linalg.det(K)) < 1e-9:
        raise ValueError('CameraInfo has a NaN, infinite or singular K/P')
    Rt = np.linalg.solve(K, P)
    U, _, Vt = np.linalg.svd(Rt[:, :3])
    R = U @ Vt
    if np.linalg.det(R) < 0 or not np.allclose(R, Rt[:, :3], atol=1e-5):
        raise ValueError('CameraInfo p is not K [R | t] with a proper rotation')
    d = list(msg.d) + [0.0] * max(0, 5 - len(msg.d))
    return Camera(K, pose_matrix(R, Rt[:, 3]), int(msg.width), int(msg.height), np.array(d[:5]))


def _pose(T: np.ndarray):
    x, y, z, w = Rotation.from_matrix(T[:3, :3]).as_quat()
    return _T['geometry_msgs/msg/Pose'](
        position=_T['geometry_msgs/msg/Point'](x=float(T[0, 3]), y=float(T[1, 3]), z=float(T[2, 3])),
        orientation=_T['geometry_msgs/msg/Quaternion'](x=float(x), y=float(y), z=float(z), w=float(w)))


def pose_msg(camera: Camera, hdr):
    """Camera pose world_T_cam as geometry_msgs/PoseStamped."""
    return _T['geometry_msgs/msg/PoseStamped'](header=hdr, pose=_pose(camera.world_T_cam))


def pose_to_matrix(pose) -> np.ndarray:
    """geometry_msgs/Pose -> (4, 4)."""
    q, p = pose.orientation, pose.position
    return pose_matrix(Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix(), [p.x, p.y, p.z])


def pedestrians_msg(positions: dict, hdr):
    """person id -> (3,) metres as PoseArray (ordered by id) and the matching Int32MultiArray of ids."""
    ids = sorted(positions)
    poses = [_pose(pose_matrix(np.eye(3), np.asarray(positions[i], dtype=float))) for i in ids]
    layout = _T['std_msgs/msg/MultiArrayLayout'](dim=[], data_offset=0)
    return (_T['geometry_msgs/msg/PoseArray'](header=hdr, poses=poses),
            _T['std_msgs/msg/Int32MultiArray'](layout=layout, data=np.array(ids, dtype=np.int32)))
