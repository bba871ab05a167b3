"""``calib``: per-drone camera calibration from the ground checkerboards, every frame (``matrix_core.calib``).

Per drone ``V`` (``views``; empty: the drone of the node's namespace), relative topics: subscribes ``V/image_raw``
or ``V/image/compressed`` (``compressed``), optionally ``V/<intrinsics_topic>`` (CameraInfo: K, D, size) and,
with ``use_registration``, ``V/homography``: an image waits up to ``registration_wait_s`` for its registration,
whose implied camera predicts the boards (else the image motion does). With register in one process
(``matrix_ros.drone_link``; calib on its own thread) both come from register, the image decoded once. Publishes
``V/camera_info`` (``p = K [R | t]``), ``V/pose`` (also on ``/tf``: world -> the image's optical frame), a
``calib/V`` status per image on ``/diagnostics``, stamped as the image (stale: the last good pose,
``publish_stale``); bad input is reported, the node keeps running. Without ``config`` the site's boards and
each drone's own camera (``matrix_core.site.calib_scene``). A drone whose ``prior_dataset`` reference (with
``site_references``: the site file's)
cannot be read is left out at start, logged and reported (``calib/V/start_up``, ``matrix_ros.left_out``); the
others are served, and the node exits when none is left.
"""

import time

from geometry_msgs.msg import PoseStamped
from matrix_msgs.msg import HomographyStamped
from rclpy.clock import Clock, ClockType
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from matrix_calib.settings import CalibNodeSettings
from matrix_core import topics
from matrix_core.calib.prior import initial_prior
from matrix_core.calib.scene import load_scene
from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.status import CalibStatus
from matrix_core.datasets import DatasetError
from matrix_core.datasets.drone_inputs import open_references, unreadable_drones
from matrix_core.geometry.camera import check_intrinsics
from matrix_core.site.calib_scene import site_calib_scene
from matrix_core.site.parameter import named_site
from matrix_core.site.shipped import matrix_site
from matrix_core.sync import FrameSynchronizer, FrameSyncSettings
from matrix_ros import diagnostics
from matrix_ros.connect import SubscribeWhenConnected
from matrix_core.message_fields import ConversionError, image_from_msg, registration_from_msg, stamp_seconds
from matrix_ros.conversions import camera_to_camera_info, camera_to_pose
from matrix_ros.drone_link import DroneLink
from matrix_ros.left_out import LeftOutReport, served_drones
from matrix_ros.node_settings import hosted_drones
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name
from matrix_ros.vision_messages import pose_transform, tf_msg


class CalibNode(SettingsNode):
    def __init__(self, defaults: CalibNodeSettings, link: DroneLink = None):
        super().__init__('calib')
        # in one process with register (link), it hands over each decoded image and its registration
        self.link = link.connect(self._on_image, self._on_registration) if link else DroneLink()
        self.settings = s = declare_settings(self, CalibNodeSettings, defaults, shared=self.link.parameters)
        s.apply_threads()
        self.own_thread = self.link.own_thread(self, s.thread_niceness)  # then spin_nodes spins it on its own thread
        # no config: the boards of the site and each drone's own camera; for MATRIX the shipped real-sample scene
        site = named_site(s.site)
        self.scene = (
            load_scene(s.config) if s.config else site_calib_scene(site) if site.path == matrix_site().path else None
        )
        self.scenes = {}  # view -> its scene
        reference = open_references(s.prior_dataset, site if s.site_references else None)
        self.calibrators, self.pubs, self.syncs, self.connections = {}, {}, {}, {}
        self.diag_pub = self.create_publisher(diagnostics.DiagnosticArray, topics.DIAGNOSTICS_TOPIC, publisher_qos())
        self.tf_pub = self.create_publisher(TFMessage, topics.TF_TOPIC, publisher_qos('reliable', 100))
        hosted = hosted_drones(self, s.views)
        # a drone whose reference prior cannot be read is left out and reported; the others are served
        left_out = unreadable_drones(reference, [v for v, _ in hosted]) if reference and reference.has_reference else {}
        for view, prefix in served_drones(self, hosted, left_out):
            self.scenes[view] = scene = self.scene or site_calib_scene(site, site.drone(view))
            self.calibrators[view] = DroneCalibrator(scene, s, *self._prior(view, reference))
            self.pubs[view] = (
                self.create_publisher(CameraInfo, topics.drone_topic(prefix, topics.CAMERA_INFO), publisher_qos()),
                self.create_publisher(PoseStamped, topics.drone_topic(prefix, topics.POSE), publisher_qos()),
            )
            if s.intrinsics_topic:
                self.create_subscription(
                    CameraInfo,
                    topics.drone_topic(prefix, s.intrinsics_topic),
                    lambda m, v=view: self._on_intrinsics(v, m),
                    10,
                )
            self._subscribe(view, prefix)
        self.left_out = LeftOutReport(self, left_out, self.diag_pub)
        if s.use_registration:  # waits on the wall clock (sim time stops in lockstep), checked to 5 % of their length
            period = min(1.0, max(0.05, s.registration_wait_s / 20))  # (20 Hz cost an idle node 3.6 % of a core)
            self.create_timer(period, self._poll, clock=Clock(clock_type=ClockType.STEADY_TIME))
        boards = len(self.scene.boards if self.scene else site.boards)
        self.get_logger().info(
            f'calibrating {sorted(self.calibrators)} with {boards} boards'
            + (', guided by their registrations' if s.use_registration else '')
        )

    def _subscribe(self, view: str, prefix: str) -> None:
        """Its images, and registrations (``use_registration``; the images once those have a publisher)."""
        s = self.settings
        if s.use_registration:
            self.syncs[view] = FrameSynchronizer(FrameSyncSettings(['image', 'registration'], s.registration_wait_s))
        if self.link.shared:
            return

        def subscribe_images():
            self.create_subscription(
                CompressedImage if s.compressed else Image,
                topics.drone_topic(prefix, topics.image_stream(s.compressed)),
                lambda m: self._on_image(view, m),
                qos_by_name(s.qos),
            )

        if not s.use_registration:
            subscribe_images()
            return
        registrations = self.create_subscription(
            HomographyStamped,
            topics.drone_topic(prefix, topics.HOMOGRAPHY),
            lambda m: self._on_registration(view, m),
            10,
        )
        self.connections[view] = SubscribeWhenConnected(self, view, [registrations], subscribe_images)

    def _prior(self, view, reference) -> tuple:
        try:
            return initial_prior(self.scenes[view], view, reference)
        except DatasetError as exc:
            self.get_logger().error(f'{view}: {exc}; every frame will be reported failed')
        return None, None

    def _on_intrinsics(self, view: str, msg: CameraInfo):
        size, d = (int(msg.width), int(msg.height)), (list(msg.d) + [0.0] * 5)[:5]
        try:
            K = check_intrinsics(msg.k, d, size, f'{view} CameraInfo')
            if self.calibrators[view].set_intrinsics(K, d, size):
                self.get_logger().info(
                    f'{view}: intrinsics from {self.settings.intrinsics_topic}: fx {K[0, 0]:.2f}, {size[0]}x{size[1]}'
                )
        except ValueError as exc:
            self.get_logger().error(f'{view}: CameraInfo intrinsics ignored: {exc}')

    def _on_image(self, view: str, msg, image=None, received=None):
        if view not in self.calibrators:  # register of this process serves a drone this node left out
            return
        item = (msg, received or time.perf_counter(), image)  # image: decoded by register in this process, else None
        if view not in self.syncs:
            return self._calibrate(view, *item)
        stamp = stamp_seconds(msg.header.stamp)
        self._restart_sync(view, stamp)
        self._synced(view, self.syncs[view].add('image', stamp, item, time.monotonic()))

    def _on_registration(self, view: str, msg: HomographyStamped):
        sync, stamp = self.syncs.get(view), stamp_seconds(msg.header.stamp)
        if sync is None:  # not guided by registrations (use_registration false)
            return
        self._restart_sync(view, stamp)
        late, frames = sync.late_items, sync.add('registration', stamp, msg, time.monotonic())  # late: before adding
        if sync.late_items > late:
            self.get_logger().warning(
                f'{view}: registration of t={stamp:.3f} s came after its image was calibrated without it; ignored'
            )
        self._synced(view, frames)

    def _restart_sync(self, view: str, stamp: float) -> None:
        """Time went back (by the drone's calibrator's detector, fed what it calibrated): the old run's pending
        images are calibrated first, then the calibrator and the synchroniser start the new run afresh."""
        calibrator = self.calibrators[view]
        if calibrator.restart.is_back(stamp):
            self._synced(view, self.syncs[view].restart())
            calibrator.check_restart(stamp)

    def _poll(self):
        for view, sync in self.syncs.items():
            self._synced(view, sync.poll(time.monotonic()))

    def _synced(self, view: str, frames: list) -> None:
        """Calibrate each image of ``frames`` (stamp order) with its registration when it came."""
        for frame in frames:
            if 'image' not in frame.items:
                self.get_logger().warning(f'{view}: registration of t={frame.stamp:.3f} s without its image')
                continue
            registration = registration_from_msg(frame.items['registration']) if 'registration' in frame.items else None
            if registration is None or not registration.ok:
                why = (
                    f'no registration of t={frame.stamp:.3f} s within {self.settings.registration_wait_s} s:'
                    if registration is None
                    else f't={frame.stamp:.3f} s: registration {registration.status}: {registration.message};'
                )
                self.get_logger().warning(f'{view}: {why} calibrated from the image motion')
            self._calibrate(view, *frame.items['image'], registration)

    def _calibrate(self, view: str, msg, received: float, image=None, registration=None):
        stamp = msg.header.stamp
        try:
            image = image_from_msg(msg) if image is None else image
            result = self.calibrators[view].process(image, stamp_seconds(stamp), registration)
        except (ConversionError, ValueError) as exc:
            self.get_logger().error(f'{view}: image at {stamp_seconds(stamp):.3f} s skipped: {exc}')
            bad = CalibStatus.BAD_INPUT
            self._diagnose(view, stamp, diagnostics.ERROR, f'{bad}: {exc}', {'status': str(bad)})
            return
        if result.camera is not None and (result.status is CalibStatus.OK or self.settings.publish_stale):
            info_pub, pose_pub = self.pubs[view]
            optical = msg.header.frame_id or topics.optical_frame(view)
            info_pub.publish(camera_to_camera_info(result.camera, Header(stamp=stamp, frame_id=optical)))
            pose = camera_to_pose(result.camera, Header(stamp=stamp, frame_id=self.settings.world_frame))
            pose_pub.publish(pose)
            self.tf_pub.publish(tf_msg(pose_transform(pose, optical)))  # the same pose, for viewers and tf2
        levels = {CalibStatus.OK: diagnostics.OK, CalibStatus.FAILED: diagnostics.ERROR}  # stale: a warning
        level = levels.get(result.status, diagnostics.WARN)
        self._diagnose(
            view,
            stamp,
            level,
            result.message,
            {**result.diagnostics(), 'latency_s': f'{time.perf_counter() - received:.3f}'},
        )
        if result.status is not CalibStatus.OK:
            self.get_logger().warning(f'{view}: {result.status}: {result.message}')

    def _diagnose(self, view: str, stamp, level, message: str, values: dict) -> None:
        """One DiagnosticStatus ``calib/<view>`` per image (stamp = the image's), whatever the outcome."""
        self.diag_pub.publish(
            diagnostics.array(stamp, diagnostics.status(f'calib/{view}', level, message, values, view))
        )


def main(argv=None) -> int:
    return spin_node(CalibNode, CalibNodeSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
