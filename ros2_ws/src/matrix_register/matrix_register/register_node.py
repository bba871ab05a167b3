"""``register``: registers each drone's live image to its reference image and publishes homographies.

Per view ``V`` in ``views`` (several drones per process; one per namespace works too):

- subscribes ``/V/<image_topic>`` (sensor_msgs/Image, or CompressedImage on ``/V/image/compressed`` when
  ``compressed``), and ``/V/<camera_info_topic>`` when no ``reference_dataset`` is configured (the
  images are then subscribed once that stream has a publisher, so that no CameraInfo is lost at start-up:
  ``matrix_ros.connect``);
- publishes ``/V/homography`` (matrix_msgs/HomographyStamped, with the image's header stamp) and
  ``/diagnostics`` (diagnostic_msgs/DiagnosticArray: status, confidence, inliers, reference, re-keying).

Reference: ``reference_dataset``'s ``reference/`` image and calibration of ``V`` (MATRIX ships one per
drone; its ``matrix_tracker_meta.json`` also gives the obstacles, see ``matrix_core.register.scene``), or
else the first image whose CameraInfo (``p = K [R | t]``, see ``matrix_ros.conversions``) has the SAME
header stamp, in whichever order the two arrive: a calibration of another instant would make every
homography wrong. Images that wait for their CameraInfo are held (at most ``PENDING`` per view); one that
falls out, or is older than the reference that starts, is published as failed. The homography convention
is that of :class:`matrix_core.register.result.RegistrationResult`; failed frames are published with
status ``failed: <reason>`` and all-zero matrices (never a made-up homography).
"""

from dataclasses import dataclass, field

import cv2
import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core.datasets import DatasetError, MatrixDataset
from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.register.backends import make_backend
from matrix_core.register.registrar import Registrar
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings
from matrix_ros.connect import SubscribeWhenConnected
from matrix_ros.conversions import ConversionError, camera_info_to_camera, compressed_to_image, msg_to_image
from matrix_ros.params import declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name


@dataclass
class RegisterNodeSettings(RegisterSettings):
    """The registration settings (same names as ``matrix-tracker register`` flags) plus the node's wiring."""

    views: list[str] = field(default_factory=lambda: ['D1'], metadata={
        'help': 'drones handled by this node; topics are /<view>/...'})
    reference_dataset: str = field(default='', metadata={
        'help': 'MATRIX folder whose reference/ holds each view\'s reference image and calibration; empty: '
                'the first frame with a CameraInfo becomes the reference'})
    area: list[float] = field(default_factory=lambda: list(MATRIX_AREA), metadata={
        'help': 'scene ground x_min y_min x_max y_max (internal world metres); overridden by reference_dataset'})
    image_topic: str = field(default='image_raw', metadata={'help': 'image topic under /<view>/'})
    compressed: bool = field(default=False, metadata={'help': 'subscribe /<view>/image/compressed instead'})
    camera_info_topic: str = field(default='camera_info', metadata={
        'help': 'CameraInfo topic under /<view>/ (used only without reference_dataset)'})
    qos: str = field(default='reliable', metadata={
        'help': 'QoS of the image subscriptions: reliable (large images survive) or sensor_data (best effort)'})
    threads: int = field(default=1, metadata={
        'help': 'OpenCV worker threads of this process (1: one core; idle pool threads of many processes on '
                'few cores cost CPU)'})

    def __post_init__(self):
        super().__post_init__()
        qos_by_name(self.qos)
        if self.threads < 1:
            raise ValueError('threads must be >= 1')
        if not self.views:
            raise ValueError('views must name at least one drone, e.g. [D1]')
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')


PENDING = 5  # images per view held while waiting for the CameraInfo of the same stamp
CAMERA_INFOS = 50  # CameraInfos per view kept to pair with later images


def _flat(H) -> list:
    return [0.0] * 9 if H is None else [float(v) for v in np.asarray(H).reshape(-1)]


def _key(stamp) -> tuple:
    return (int(stamp.sec), int(stamp.nanosec))


def _stamp_text(stamp) -> str:
    return f'{stamp.sec}.{stamp.nanosec:09d}'


class RegisterNode(Node):
    def __init__(self, defaults: RegisterNodeSettings):
        super().__init__('register')
        self.settings = s = declare_settings(self, RegisterNodeSettings, defaults)
        cv2.setNumThreads(s.threads)
        self.backend = make_backend(s)
        self.registrars, self.pubs, self.connections = {}, {}, {}
        self.camera_infos = {v: {} for v in s.views}  # view -> {stamp key: CameraInfo}
        self.pending = {v: {} for v in s.views}  # view -> {stamp key: (msg, image)} waiting for a CameraInfo
        self.area = tuple(s.area)
        dataset = MatrixDataset(s.reference_dataset) if s.reference_dataset else None
        if dataset is not None:
            self.area = dataset.area
            self.settings, note = settings_for_dataset(s, dataset)
            s = self.settings
            if note:
                self.get_logger().info(note)
        qos = qos_by_name(s.qos)
        for view in s.views:
            if dataset is not None:
                path = dataset.reference_image_path(view)
                image = cv2.imread(str(path), cv2.IMREAD_COLOR)
                if image is None:
                    raise DatasetError(f'cannot decode reference image {path}')
                self.registrars[view] = Registrar(s, image, dataset.reference_camera(view), self.area,
                                                  f'{view}/reference', self.backend)
            self._subscribe_view(view, qos, needs_camera_info=dataset is None)
            self.pubs[view] = self.create_publisher(HomographyStamped, f'/{view}/homography', publisher_qos())
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', publisher_qos())
        self.get_logger().info(f'registering {s.views} with backend {self.backend.name} at scale {s.scale}; '
                               f'reference: {s.reference_dataset or "first frame with CameraInfo"}')

    def _subscribe_view(self, view: str, qos, needs_camera_info: bool) -> None:
        """The view's images; without a reference dataset they wait for its CameraInfo stream to connect
        (its first CameraInfo makes the reference: matrix_ros.connect)."""
        s = self.settings

        def subscribe_images():
            if s.compressed:
                self.create_subscription(CompressedImage, f'/{view}/image/compressed',
                                         lambda m: self._on_image(view, m, compressed_to_image), qos)
            else:
                self.create_subscription(Image, f'/{view}/{s.image_topic}',
                                         lambda m: self._on_image(view, m, msg_to_image), qos)
        if not needs_camera_info:
            subscribe_images()
            return
        info = self.create_subscription(CameraInfo, f'/{view}/{s.camera_info_topic}',
                                        lambda m: self._on_camera_info(view, m), 10)
        self.connections[view] = SubscribeWhenConnected(self, view, [info], subscribe_images)

    def _on_camera_info(self, view: str, msg: CameraInfo) -> None:
        if view in self.registrars:
            return
        infos = self.camera_infos[view]
        infos[_key(msg.header.stamp)] = msg
        while len(infos) > CAMERA_INFOS:
            infos.pop(min(infos))
        held = self.pending[view].pop(_key(msg.header.stamp), None)
        if held is not None:
            self._start_reference(view, *held)

    def _start_reference(self, view: str, msg, image) -> None:
        """Make ``image`` (with its same-stamp CameraInfo) the reference, then register it and the held images."""
        stamp = msg.header.stamp
        info = self.camera_infos[view].pop(_key(stamp))
        try:
            camera = camera_info_to_camera(info)
            self.registrars[view] = Registrar(self.settings, image, camera, self.area,
                                              f'{view}/frame/{_stamp_text(stamp)}', self.backend)
        except (ConversionError, ValueError) as exc:
            self._bad_input(view, msg, f'cannot make it the reference: {exc}')
            return
        self.camera_infos[view].clear()
        self.get_logger().info(f'{view}: reference is the image at {_stamp_text(stamp)} (its CameraInfo)')
        self._publish(view, msg, self.registrars[view].reference_result())
        for key in sorted(self.pending[view]):
            held_msg, held_image = self.pending[view].pop(key)
            if key < _key(stamp):
                self._publish_failed(view, held_msg, 'arrived before the reference image (no CameraInfo of its stamp)')
            else:
                self._register(view, held_msg, held_image)

    def _hold(self, view: str, msg, image) -> None:
        """Keep an image until its CameraInfo arrives; the oldest held image is failed when too many wait."""
        pending = self.pending[view]
        pending[_key(msg.header.stamp)] = (msg, image)
        self.get_logger().warning(f'{view}: no reference yet (waiting for a /{view}/{self.settings.camera_info_topic}'
                                  f' with the stamp of an image)', throttle_duration_sec=5.0)
        while len(pending) > PENDING:
            old_msg, _ = pending.pop(min(pending))
            self._publish_failed(view, old_msg, f'no reference: no CameraInfo with stamp '
                                                f'{_stamp_text(old_msg.header.stamp)} arrived')

    def _on_image(self, view: str, msg, decode) -> None:
        try:
            image = decode(msg)
        except (ConversionError, ValueError) as exc:
            self._bad_input(view, msg, str(exc))
            return
        if view in self.registrars:
            self._register(view, msg, image)
        elif _key(msg.header.stamp) in self.camera_infos[view]:
            self._start_reference(view, msg, image)
        else:
            self._hold(view, msg, image)

    def _bad_input(self, view: str, msg, text: str) -> None:
        """An undecodable image still gets its (failed) homography: the fuse node need not wait for it."""
        self.get_logger().error(f'{view}: image at {_stamp_text(msg.header.stamp)} not registered: {text}')
        self.pubs[view].publish(self._failed(msg.header, f'bad input: {text}'))
        self._diagnose(view, msg.header, DiagnosticStatus.ERROR, f'bad input: {text}', None)

    def _failed(self, header, reason: str) -> HomographyStamped:
        out = HomographyStamped(header=header)
        out.h_cur_to_ref, out.h_img_to_ground = _flat(None), _flat(None)
        out.status, out.backend = f'failed: {reason}', self.backend.name
        return out

    def _publish_failed(self, view: str, msg, reason: str) -> None:
        out = self._failed(msg.header, reason)
        self.pubs[view].publish(out)
        self.get_logger().warning(f'{view}: image at {_stamp_text(msg.header.stamp)} not registered: {reason}')
        self._diagnose(view, msg.header, DiagnosticStatus.WARN, out.status, None)

    def _register(self, view: str, msg, image) -> None:
        registrar = self.registrars[view]
        try:
            result = registrar.register(image, _stamp_text(msg.header.stamp))
        except ValueError as exc:
            self._bad_input(view, msg, str(exc))
            return
        self._publish(view, msg, result)

    def _publish(self, view: str, msg, result) -> None:
        out = HomographyStamped(header=msg.header)
        out.h_cur_to_ref, out.h_img_to_ground = _flat(result.H_cur_to_ref), _flat(result.H_img_to_ground)
        out.confidence, out.matches, out.inliers = float(result.confidence), result.matches, result.inliers
        out.inlier_error_px = float(result.inlier_error_px) if np.isfinite(result.inlier_error_px) else 0.0
        out.status = 'ok' if result.ok else f'failed: {result.message}'
        out.reference_id, out.backend = result.reference_id, result.backend
        self.pubs[view].publish(out)
        if not result.ok:
            self.get_logger().warning(f'{view}: registration failed: {result.message}')
        level = DiagnosticStatus.OK if result.ok else DiagnosticStatus.WARN
        self._diagnose(view, msg.header, level, out.status + (f' ({result.message})' if result.ok and
                                                               result.message else ''), result)

    def _diagnose(self, view, header, level, text, result) -> None:
        status = DiagnosticStatus(level=level, name=f'register/{view}', message=text[:250],
                                  hardware_id=view)
        if result is not None:
            status.values = [KeyValue(key=k, value=str(v)) for k, v in (
                ('confidence', f'{result.confidence:.3f}'), ('matches', result.matches),
                ('inliers', result.inliers), ('reference_id', result.reference_id),
                ('backend', result.backend), ('seconds', f'{result.seconds:.3f}'),
                ('message', result.message))]
        self.diag_pub.publish(DiagnosticArray(header=header, status=[status]))


def main(argv=None) -> int:
    return spin_node(RegisterNode, RegisterNodeSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
