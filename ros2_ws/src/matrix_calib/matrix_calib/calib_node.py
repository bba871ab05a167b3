"""``calib``: per-drone camera calibration from the ground checkerboards, every frame.

Per drone ``V`` (``views`` lists several drones in one process; empty = one drone in the node's
namespace, relative topic names):

- subscribes ``V/image_raw`` (sensor_msgs/Image) or ``V/image/compressed`` (``compressed:=true``),
  QoS ``qos`` (sensor_data by default), and optionally ``V/<intrinsics_topic>`` (sensor_msgs/CameraInfo:
  only K, D and the size are used; default: the intrinsics of the scene config); with ``use_registration``
  also ``V/homography`` (matrix_msgs/HomographyStamped from ``register``): each image waits up to
  ``registration_wait_s`` for the registration of its stamp, whose implied camera then predicts the boards
  (``DroneCalibrator.process(..., img_H_ground)``); without one (or a failed one) the image is calibrated
  from the image motion, logged;
- publishes ``V/camera_info`` (sensor_msgs/CameraInfo: ``k``, ``d`` the intrinsics, ``p = K [R | t]``
  mapping homogeneous WORLD points (frame ``world_frame``) to pixels, see ``matrix_ros.conversions``),
  ``V/pose`` (geometry_msgs/PoseStamped: camera optical frame in ``world_frame``), and one status per
  drone on ``/diagnostics`` (diagnostic_msgs/DiagnosticArray: status ok/stale/failed, reprojection
  error, corners, pieces, age of the pose, latency).

Output stamps equal the input image stamp. Stale results (no acceptable pose in this image) republish
the last good pose when ``publish_stale`` (diagnostics say it is stale and how old); nothing is
published before the first good pose. Bad input (empty image, unknown encoding, corrupt JPEG, wrong
size) gives one error log line and an ERROR status per message, and the node keeps running: every image
gets exactly one ``calib/V`` status with its stamp (what ``graph_monitor`` counts as processed).
Publishers offer transient-local history (``matrix_ros.qos``).
"""

import time
from dataclasses import dataclass, field

import cv2
import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped
from matrix_msgs.msg import HomographyStamped
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import Header

from matrix_core.calib.scene import load_scene
from matrix_core.calib.settings import CalibSettings
from matrix_core.calib.drone_calibrator import FAILED, OK, DroneCalibrator
from matrix_core.datasets import DatasetError, MatrixDataset
from matrix_core.fusion.views import img_H_ground_from_registration
from matrix_core.sync import FrameSynchronizer, FrameSyncSettings
from matrix_ros.connect import SubscribeWhenConnected
from matrix_ros.conversions import (ConversionError, camera_to_camera_info, camera_to_pose,
                                    compressed_to_image, msg_to_image, stamp_to_seconds)
from matrix_ros.params import declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name


@dataclass
class CalibNodeSettings(CalibSettings):
    views: list[str] = field(default_factory=list, metadata={
        'help': 'drones hosted by this process, topics /V/...; empty = one drone in the node namespace'})
    compressed: bool = field(default=False, metadata={'help': 'subscribe image/compressed instead of image_raw'})
    qos: str = field(default='sensor_data', metadata={'help': 'QoS of the image subscription: sensor_data or reliable'})
    world_frame: str = field(default='world', metadata={'help': 'frame_id of the published pose'})
    publish_stale: bool = field(default=True, metadata={
        'help': 'republish the last good pose (stamped with the new image) when this image gave none'})
    intrinsics_topic: str = field(default='', metadata={
        'help': 'per-drone CameraInfo topic (relative to /V/, e.g. ground_truth/camera_info) whose k, d and '
                'size replace the config intrinsics; its extrinsics are ignored; empty = config only'})
    threads: int = field(default=1, metadata={
        'help': 'OpenCV worker threads of this process (1: one core; idle pool threads of many processes on '
                'few cores cost CPU)'})
    use_registration: bool = field(default=False, metadata={
        'help': "pair each image with the drone's registration of the same stamp (V/homography, "
                'matrix_msgs/HomographyStamped from register) and let the camera it implies guide the calibration '
                '(track_registered: about 0.1 s instead of 0.5 s per 1080p frame); images are subscribed once that '
                'stream has a publisher'})
    registration_wait_s: float = field(default=3.0, metadata={
        'help': 'with use_registration: seconds (wall clock) an image waits for its registration before it is '
                'calibrated from the image motion instead (logged)'})
    prior_dataset: str = field(default='', metadata={
        'help': 'MATRIX folder whose reference/calibrations (and reference images) give the first prior; '
                'empty = the config\'s initial_poses'})

    def __post_init__(self):
        super().__post_init__()
        qos_by_name(self.qos)
        if self.threads < 1:
            raise ValueError('threads must be >= 1')
        if self.registration_wait_s <= 0:
            raise ValueError('registration_wait_s must be positive')


class CalibNode(Node):
    def __init__(self, defaults: CalibNodeSettings):
        super().__init__('calib')
        self.settings = s = declare_settings(self, CalibNodeSettings, defaults)
        cv2.setNumThreads(s.threads)
        self.scene = load_scene(s.config)
        namespace_view = self.get_namespace().strip('/').split('/')[-1]
        drones = [(v, f'/{v}/') for v in s.views] or [(namespace_view or 'camera', '')]
        reference = MatrixDataset(s.prior_dataset) if s.prior_dataset else None
        self.calibrators, self.pubs, self.syncs, self.connections = {}, {}, {}, {}
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', publisher_qos())
        for view, prefix in drones:
            prior, image = self._prior(view, reference)
            self.calibrators[view] = DroneCalibrator(self.scene, s, prior, image)
            self.pubs[view] = (self.create_publisher(CameraInfo, f'{prefix}camera_info', publisher_qos()),
                               self.create_publisher(PoseStamped, f'{prefix}pose', publisher_qos()))
            if s.intrinsics_topic:
                self.create_subscription(CameraInfo, f'{prefix}{s.intrinsics_topic}',
                                         lambda m, v=view: self._on_intrinsics(v, m), 10)
            self._subscribe(view, prefix)
        if s.use_registration:   # registration waits run on the wall clock: sim time stops in lockstep
            self.create_timer(0.05, self._poll, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(f'calibrating {sorted(self.calibrators)} with {len(self.scene.boards)} boards'
                               + (', guided by their registrations' if s.use_registration else ''))

    def _subscribe(self, view: str, prefix: str) -> None:
        """The drone's images; with ``use_registration`` also its registrations, and the images only once
        those have a publisher (matrix_ros.connect)."""
        s = self.settings

        def subscribe_images():
            qos = qos_by_name(s.qos)
            if s.compressed:
                self.create_subscription(CompressedImage, f'{prefix}image/compressed',
                                         lambda m: self._on_image(view, m, compressed=True), qos)
            else:
                self.create_subscription(Image, f'{prefix}image_raw',
                                         lambda m: self._on_image(view, m, compressed=False), qos)
        if not s.use_registration:
            subscribe_images()
            return
        self.syncs[view] = FrameSynchronizer(FrameSyncSettings(['image', 'registration'], s.registration_wait_s))
        registrations = self.create_subscription(HomographyStamped, f'{prefix}homography',
                                                 lambda m: self._on_registration(view, m), 10)
        self.connections[view] = SubscribeWhenConnected(self, view, [registrations], subscribe_images)

    def _prior(self, view, reference):
        if reference is not None:
            try:
                img = cv2.imread(str(reference.reference_image_path(view)))
                return reference.reference_camera(view), img
            except DatasetError as exc:
                self.get_logger().warning(f'{view}: no reference prior in {reference.root}: {exc}')
        if view in self.scene.initial_poses:
            return self.scene.initial_poses[view], None
        self.get_logger().error(f'{view}: no prior pose (set prior_dataset or initial_poses in the config); '
                                'every frame will be reported failed')
        return None, None

    def _on_intrinsics(self, view: str, msg: CameraInfo):
        cal = self.calibrators[view]
        K = np.array(msg.k, dtype=np.float64).reshape(3, 3)
        d = (list(msg.d) + [0.0] * 5)[:5]
        size = (int(msg.width), int(msg.height))
        if not np.all(np.isfinite(K)) or not np.all(np.isfinite(d)) or abs(np.linalg.det(K)) < 1e-9 or min(size) <= 0:
            self.get_logger().error(f'{view}: CameraInfo intrinsics ignored (NaN, singular K or empty size)')
            return
        if not (np.allclose(K, cal.scene.K) and np.allclose(d, cal.scene.dist) and size == tuple(cal.scene.image_size)):
            cal.set_intrinsics(K, d, size)
            self.get_logger().info(f'{view}: intrinsics from {self.settings.intrinsics_topic}: fx {K[0, 0]:.2f}, '
                                   f'{size[0]}x{size[1]}')

    def _on_image(self, view: str, msg, compressed: bool):
        received = time.perf_counter()
        if view not in self.syncs:
            self._calibrate(view, msg, compressed, received)
            return
        self._synced(view, self.syncs[view].add('image', stamp_to_seconds(msg.header.stamp),
                                                (msg, compressed, received), time.monotonic()))

    def _on_registration(self, view: str, msg: HomographyStamped):
        sync = self.syncs[view]
        late = sync.late_items
        frames = sync.add('registration', stamp_to_seconds(msg.header.stamp), msg, time.monotonic())
        if sync.late_items > late:
            self.get_logger().warning(f'{view}: registration of t={stamp_to_seconds(msg.header.stamp):.3f} s came '
                                      f'after its image was calibrated without it; ignored')
        self._synced(view, frames)

    def _poll(self):
        for view, sync in self.syncs.items():
            self._synced(view, sync.poll(time.monotonic()))

    def _synced(self, view: str, frames: list) -> None:
        """Calibrate each image of ``frames`` (stamp order) with its registration when it came."""
        for frame in frames:
            if 'image' not in frame.items:
                self.get_logger().warning(f'{view}: registration of t={frame.stamp:.3f} s without its image')
                continue
            msg, compressed, received = frame.items['image']
            registration = frame.items.get('registration')
            img_H_ground = None
            if registration is None:
                self.get_logger().warning(f'{view}: no registration of t={frame.stamp:.3f} s within '
                                          f'{self.settings.registration_wait_s} s: calibrated from the image motion')
            elif registration.status != 'ok':
                self.get_logger().warning(f'{view}: t={frame.stamp:.3f} s: registration {registration.status}; '
                                          'calibrated from the image motion')
            else:
                try:
                    img_H_ground = img_H_ground_from_registration(registration.h_img_to_ground)
                except (ValueError, np.linalg.LinAlgError) as exc:   # the calibrator says why it is not used
                    self.get_logger().error(f'{view}: t={frame.stamp:.3f} s: registration homography unusable: {exc}')
                    img_H_ground = np.full((3, 3), np.nan)
            self._calibrate(view, msg, compressed, received, img_H_ground)

    def _calibrate(self, view: str, msg, compressed: bool, received: float, img_H_ground=None):
        try:
            image = compressed_to_image(msg) if compressed else msg_to_image(msg)
            result = self.calibrators[view].process(image, stamp_to_seconds(msg.header.stamp), img_H_ground)
        except (ConversionError, ValueError) as exc:
            self.get_logger().error(f'{view}: image at {stamp_to_seconds(msg.header.stamp):.3f} s skipped: {exc}')
            self._diagnose(view, msg.header.stamp, DiagnosticStatus.ERROR, f'bad input: {exc}', {'status': 'bad_input'})
            return
        latency = time.perf_counter() - received
        header = Header(stamp=msg.header.stamp, frame_id=msg.header.frame_id or f'{view}/camera_optical')
        if result.camera is not None and (result.status == OK or self.settings.publish_stale):
            info_pub, pose_pub = self.pubs[view]
            info_pub.publish(camera_to_camera_info(result.camera, header))
            pose_pub.publish(camera_to_pose(result.camera, Header(stamp=msg.header.stamp,
                                                                  frame_id=self.settings.world_frame)))
        level = {OK: DiagnosticStatus.OK, FAILED: DiagnosticStatus.ERROR}.get(result.status, DiagnosticStatus.WARN)
        self._diagnose(view, msg.header.stamp, level, result.message, {
            'status': result.status, 'reprojection_rms_px': f'{result.rms_px:.3f}',
            'corners': str(result.corners), 'pieces_found': str(result.pieces_found),
            'pieces_assigned': str(result.pieces_assigned), 'age_s': f'{result.age_s:.3f}',
            'latency_s': f'{latency:.3f}', 'full_search': str(result.full_search), 'tracked': str(result.tracked),
            'guide': result.motion})
        if result.status != OK:
            self.get_logger().warning(f'{view}: {result.status}: {result.message}')

    def _diagnose(self, view: str, stamp, level, message: str, values: dict) -> None:
        """One DiagnosticStatus ``calib/<view>`` per image (stamp = the image's), whatever the outcome."""
        status = DiagnosticStatus(level=level, name=f'calib/{view}', message=message[:250], hardware_id=view,
                                  values=[KeyValue(key=k, value=v) for k, v in values.items()])
        self.diag_pub.publish(DiagnosticArray(header=Header(stamp=stamp), status=[status]))


def main(argv=None) -> int:
    return spin_node(CalibNode, CalibNodeSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
