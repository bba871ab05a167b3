"""``register``: registers each drone's live image to its reference image and publishes its registration.

Per view ``V`` in ``views`` (several drones per process), relative topics (``matrix_core.topics``):

- subscribes ``V/<image_topic>`` (sensor_msgs/Image, or CompressedImage on ``V/image/compressed`` when
  ``compressed``), and ``V/<camera_info_topic>`` when no ``reference_dataset`` is configured (the images once
  that stream has a publisher, so that no CameraInfo is lost at start-up: ``matrix_ros.connect``);
- publishes ``V/homography`` (matrix_msgs/HomographyStamped, the message form of ``matrix_core.register.
  registration.Registration``, the image's stamp) and ``/diagnostics`` (confidence, inliers, reference, ...).

Reference: ``reference_dataset``'s ``reference/`` image and calibration of ``V`` (its
``matrix_tracker_meta.json`` also gives the obstacles, see ``matrix_core.register.scene``), with
``site_references`` the site file's (``matrix_core.datasets.drone_inputs.open_references``), or else the first
image whose CameraInfo (``p = K [R | t]``) has the SAME stamp (``matrix_core.register.reference_pairing``). A
drone whose reference cannot be read is left out at start, logged and reported on ``/diagnostics``
(``register/V/start_up``, ``matrix_ros.left_out``); the others are served, and the node exits when none is left.
Failed and undecodable frames are published failed with their reason (never a made-up homography), so that the
fuse node need not wait for them. In one process with calib (``matrix_ros.drone_link``) each image is decoded
once, grey, and handed to calib with its registration. A reference dataset's first drone warms the process up.
"""

from matrix_msgs.msg import HomographyStamped
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core import topics
from matrix_core.datasets.drone_inputs import open_references, unreadable_drones
from matrix_core.register.backends import make_backend
from matrix_core.register.reference_pairing import FAIL, HOLD, REFERENCE, ReferencePairing, stamp_text
from matrix_core.register.registrar import Registrar
from matrix_core.register.registration import Registration, RegistrationStatus
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.warm_up import warm_up_once
from matrix_core.site.parameter import named_site
from matrix_register.settings import RegisterNodeSettings
from matrix_ros import diagnostics
from matrix_ros.connect import SubscribeWhenConnected
from matrix_core.message_fields import ConversionError, camera_from_camera_info, stamp_ns
from matrix_ros.conversions import registration_to_msg
from matrix_ros.drone_link import DroneLink
from matrix_ros.left_out import LeftOutReport, served_drones
from matrix_ros.node_settings import hosted_drones
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name
from matrix_ros.restarts import DroneRestarts


class RegisterNode(SettingsNode):
    def __init__(self, defaults: RegisterNodeSettings, link: DroneLink = None):
        super().__init__('register')
        self.link = link or DroneLink()  # calib of the same process, if any (matrix_bringup.drone)
        self.settings = s = declare_settings(self, RegisterNodeSettings, defaults, shared=self.link.parameters)
        s.apply_threads()
        self.backend = make_backend(s)
        self.registrars, self.pubs, self.connections, self.pairing = {}, {}, {}, {}
        self.area = tuple(s.area)
        site = named_site(s.site) if s.site_references else None
        self.dataset = dataset = open_references(s.reference_dataset, site)
        self.restarts = DroneRestarts(self, s.restart_gap_s, self._start_drone)
        if dataset is not None:
            self.area = dataset.area
            self.settings, note = settings_for_dataset(s, dataset)
            s = self.settings
            if note:
                self.get_logger().info(note)
        hosted = hosted_drones(self, s.views)
        # a drone whose reference cannot be read is left out and reported; the others are served
        left_out = unreadable_drones(dataset, [v for v, _ in hosted]) if dataset is not None else {}
        for view, prefix in served_drones(self, hosted, left_out):
            self._start_drone(view)
            self._subscribe_view(view, prefix, needs_camera_info=dataset is None)
            self.pubs[view] = self.create_publisher(
                HomographyStamped, topics.drone_topic(prefix, topics.HOMOGRAPHY), publisher_qos()
            )
        self.diag_pub = self.create_publisher(diagnostics.DiagnosticArray, topics.DIAGNOSTICS_TOPIC, publisher_qos())
        self.left_out = LeftOutReport(self, left_out, self.diag_pub)
        self.get_logger().info(
            f'registering {list(self.pubs)} with backend {self.backend.name} at scale {s.scale}; '
            f'reference: {dataset.root if dataset is not None else "first frame with CameraInfo"}'
        )

    def _subscribe_view(self, view: str, prefix: str, needs_camera_info: bool) -> None:
        """The view's images; without a reference dataset they wait for its CameraInfo stream to connect."""
        s = self.settings

        def subscribe_images():
            msg_type, stream = (CompressedImage, topics.IMAGE_COMPRESSED) if s.compressed else (Image, s.image_topic)
            self.create_subscription(
                msg_type,
                topics.drone_topic(prefix, stream),
                self.restarts.checked(view, lambda m: self._on_image(view, m)),
                qos_by_name(s.qos),
            )

        if not needs_camera_info:
            subscribe_images()
            return
        info = self.create_subscription(
            CameraInfo,
            topics.drone_topic(prefix, s.camera_info_topic),
            self.restarts.checked(
                view, lambda m: self._run(view, self.pairing[view].camera_info(stamp_ns(m.header), m))
            ),
            10,
        )
        self.connections[view] = SubscribeWhenConnected(self, view, [info], subscribe_images)

    def _start_drone(self, view: str) -> None:
        """The drone's reference (dataset's, or first frame with a CameraInfo); again when a replay restarts."""
        self.pairing[view], d = ReferencePairing(), self.dataset
        self.registrars.pop(view, None)
        if d is not None:  # the process's first registration pays for first calls: at start-up, not on a frame
            image, camera, name = d.reference_image(view), d.reference_camera(view), f'{view}/reference'
            warm_up_once(self.settings, image, camera, self.area, self.backend)
            self.registrars[view] = Registrar(self.settings, image, camera, self.area, name, self.backend)

    def _on_image(self, view: str, msg) -> None:
        try:
            image = self.link.decode(msg)
        except (ConversionError, ValueError) as exc:
            self.link.image(view, msg, None)  # calib tries itself and reports the bad input
            return self._publish(view, msg.header, Registration.bad_input(str(exc), backend=self.backend.name))
        self.link.image(view, msg, image)
        if view in self.registrars:
            self._register(view, msg, image)
        else:
            self._run(view, self.pairing[view].image(stamp_ns(msg.header), (msg, image)))

    def _run(self, view: str, steps: list) -> None:
        """Carry out the reference pairing's steps."""
        for step in steps or []:
            msg, image = step.image
            if step.kind == HOLD:
                self.get_logger().warning(
                    f'{view}: no reference yet (waiting for a {view}/{self.settings.camera_info_topic}'
                    ' with the stamp of an image)',
                    throttle_duration_sec=5.0,
                )
            elif step.kind == FAIL:
                self._publish(view, msg.header, Registration.failed(step.reason, backend=self.backend.name))
            elif step.kind == REFERENCE:
                self._start_reference(view, step)
            else:
                self._register(view, msg, image)

    def _start_reference(self, view: str, step) -> None:
        msg, image = step.image
        text = stamp_text(step.stamp_ns)
        try:
            self.registrars[view] = Registrar(
                self.settings,
                image,
                camera_from_camera_info(step.camera_info),
                self.area,
                f'{view}/frame/{text}',
                self.backend,
            )
        except (ConversionError, ValueError) as exc:
            self._publish(
                view,
                msg.header,
                Registration.bad_input(f'cannot make it the reference: {exc}', backend=self.backend.name),
            )
            return
        self.get_logger().info(f'{view}: reference is the image at {text} (its CameraInfo)')
        self._publish(view, msg.header, self.registrars[view].reference_result(), measured=True)
        self._run(view, self.pairing[view].started_with(step.stamp_ns))

    def _register(self, view: str, msg, image) -> None:
        try:
            result = self.registrars[view].register(image, stamp_text(stamp_ns(msg.header)))
        except ValueError as exc:
            return self._publish(view, msg.header, Registration.bad_input(str(exc), backend=self.backend.name))
        self._publish(view, msg.header, result, measured=True)

    def _publish(self, view: str, header, result: Registration, measured: bool = False) -> None:
        """The registration (ok or failed) on V/homography, and its diagnostics (with the figures of a
        ``measured`` one, i.e. one the registrar computed)."""
        self.pubs[view].publish(out := registration_to_msg(result, header))
        self.link.registration(view, out)
        bad_input = result.status == RegistrationStatus.BAD_INPUT
        if not result.ok:
            log = self.get_logger().error if bad_input else self.get_logger().warning
            log(f'{view}: image at {stamp_text(stamp_ns(header))} not registered: {result.message}')
        level = diagnostics.OK if result.ok else (diagnostics.ERROR if bad_input else diagnostics.WARN)
        text = f'{result.status}' if result.ok else f'{result.status}: {result.message}'
        values = (
            ()
            if not measured
            else (
                ('confidence', f'{result.confidence:.3f}'),
                ('matches', result.matches),
                ('inliers', result.inliers),
                ('reference_id', result.reference_id),
                ('backend', result.backend),
                ('seconds', f'{result.seconds:.3f}'),
                ('message', result.message),
            )
        )
        self.diag_pub.publish(
            diagnostics.array(
                header,
                diagnostics.status(
                    f'register/{view}',
                    level,
                    text + (f' ({result.message})' if result.ok and result.message else ''),
                    values,
                    view,
                ),
            )
        )


def main(argv=None) -> int:
    return spin_node(RegisterNode, RegisterNodeSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
