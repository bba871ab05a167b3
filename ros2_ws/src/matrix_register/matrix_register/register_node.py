"""``register``: registers each drone's live image to its reference image and publishes homographies.

Per view ``V`` in ``views`` (several drones per process; one per namespace works too):

- subscribes ``/V/<image_topic>`` (sensor_msgs/Image, or CompressedImage on ``/V/image/compressed`` when
  ``compressed``), and ``/V/<camera_info_topic>`` when no ``reference_dataset`` is configured;
- publishes ``/V/homography`` (matrix_msgs/HomographyStamped, with the image's header stamp) and
  ``/diagnostics`` (diagnostic_msgs/DiagnosticArray: status, confidence, inliers, reference, re-keying).

Reference: ``reference_dataset``'s ``reference/`` image and calibration of ``V`` (MATRIX ships one per
drone), or else the first frame that arrives together with a CameraInfo (``p = K [R | t]``, see
``matrix_ros.conversions``). The homography convention is that of
:class:`matrix_core.register.result.RegistrationResult`; failed frames are published with status
``failed: <reason>`` and all-zero matrices (never a made-up homography).
"""

from dataclasses import dataclass, field

import cv2
import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core.datasets import DatasetError, MatrixDataset
from matrix_core.register.backends import make_backend
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import RegisterSettings
from matrix_ros.conversions import ConversionError, camera_info_to_camera, compressed_to_image, msg_to_image
from matrix_ros.params import declare_settings, spin_node
from matrix_ros.qos import qos_by_name


@dataclass
class RegisterNodeSettings(RegisterSettings):
    """The registration settings (same names as ``matrix-tracker register`` flags) plus the node's wiring."""

    views: list[str] = field(default_factory=lambda: ['D1'], metadata={
        'help': 'drones handled by this node; topics are /<view>/...'})
    reference_dataset: str = field(default='', metadata={
        'help': 'MATRIX folder whose reference/ holds each view\'s reference image and calibration; empty: '
                'the first frame with a CameraInfo becomes the reference'})
    area: list[float] = field(default_factory=lambda: [0.0, -30.0, 30.0, 0.0], metadata={
        'help': 'scene ground x_min y_min x_max y_max (internal world metres); overridden by reference_dataset'})
    image_topic: str = field(default='image_raw', metadata={'help': 'image topic under /<view>/'})
    compressed: bool = field(default=False, metadata={'help': 'subscribe /<view>/image/compressed instead'})
    camera_info_topic: str = field(default='camera_info', metadata={
        'help': 'CameraInfo topic under /<view>/ (used only without reference_dataset)'})
    qos: str = field(default='reliable', metadata={
        'help': 'QoS of the image subscriptions: reliable (large images survive) or sensor_data (best effort)'})

    def __post_init__(self):
        super().__post_init__()
        qos_by_name(self.qos)
        if not self.views:
            raise ValueError('views must name at least one drone, e.g. [D1]')
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')


def _flat(H) -> list:
    return [0.0] * 9 if H is None else [float(v) for v in np.asarray(H).reshape(-1)]


class RegisterNode(Node):
    def __init__(self, defaults: RegisterNodeSettings):
        super().__init__('register')
        self.settings = s = declare_settings(self, RegisterNodeSettings, defaults)
        self.backend = make_backend(s)
        self.registrars, self.camera_infos, self.pubs = {}, {}, {}
        self.area = tuple(s.area)
        dataset = MatrixDataset(s.reference_dataset) if s.reference_dataset else None
        if dataset is not None:
            self.area = dataset.area
        qos = qos_by_name(s.qos)
        for view in s.views:
            if dataset is not None:
                path = dataset.reference_image_path(view)
                image = cv2.imread(str(path), cv2.IMREAD_COLOR)
                if image is None:
                    raise DatasetError(f'cannot decode reference image {path}')
                self.registrars[view] = Registrar(s, image, dataset.reference_camera(view), self.area,
                                                  f'{view}/reference', self.backend)
            else:
                self.create_subscription(CameraInfo, f'/{view}/{s.camera_info_topic}',
                                         lambda m, v=view: self.camera_infos.__setitem__(v, m), 10)
            if s.compressed:
                self.create_subscription(CompressedImage, f'/{view}/image/compressed',
                                         lambda m, v=view: self._on_image(v, m, compressed_to_image), qos)
            else:
                self.create_subscription(Image, f'/{view}/{s.image_topic}',
                                         lambda m, v=view: self._on_image(v, m, msg_to_image), qos)
            self.pubs[view] = self.create_publisher(HomographyStamped, f'/{view}/homography', 10)
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.get_logger().info(f'registering {s.views} with backend {self.backend.name} at scale {s.scale}; '
                               f'reference: {s.reference_dataset or "first frame with CameraInfo"}')

    def _registrar(self, view: str, image: np.ndarray, stamp):
        """The view's registrar; without a configured reference, the first frame with a CameraInfo starts it."""
        if view in self.registrars:
            return self.registrars[view]
        info = self.camera_infos.get(view)
        if info is None:
            self.get_logger().warning(f'{view}: no reference yet (waiting for /{view}/'
                                      f'{self.settings.camera_info_topic})', throttle_duration_sec=5.0)
            return None
        camera = camera_info_to_camera(info)
        self.registrars[view] = Registrar(self.settings, image, camera, self.area,
                                          f'{view}/frame/{stamp.sec}.{stamp.nanosec:09d}', self.backend)
        self.get_logger().info(f'{view}: reference is the first frame with a CameraInfo')
        return self.registrars[view]

    def _on_image(self, view: str, msg, decode) -> None:
        try:
            image = decode(msg)
            registrar = self._registrar(view, image, msg.header.stamp)
        except (ConversionError, ValueError) as exc:
            self.get_logger().error(f'{view}: image at {msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d} '
                                    f'not registered: {exc}')
            self._diagnose(view, msg.header, DiagnosticStatus.ERROR, f'bad input: {exc}', None)
            return
        if registrar is None:
            return
        result = registrar.register(image, f'{msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d}')
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
                ('backend', result.backend), ('seconds', f'{result.seconds:.3f}'))]
        self.diag_pub.publish(DiagnosticArray(header=header, status=[status]))


def main(argv=None) -> int:
    return spin_node(RegisterNode, RegisterNodeSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
