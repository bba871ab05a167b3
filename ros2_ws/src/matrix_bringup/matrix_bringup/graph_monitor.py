"""``graph_monitor``: score what the running graph publishes against the ground truth, then exit.

Per view ``V`` it subscribes ``/V/camera_info`` (from ``calib``), ``/V/homography`` (from ``register``),
``/V/ground_truth/camera_info`` and ``/V/image_raw`` (from the player), and ``/diagnostics``; with QoS
``history`` (transient local), so what was published before the monitor matched still arrives.

It is also the referee of a lockstep replay: a frame is *done* when every stage in ``wait_for`` has
processed it - ``register`` / ``calib``: a ``register/V`` / ``calib/V`` diagnostic status with the frame's
stamp from every view (the nodes publish one per image, whatever the outcome), ``tracks``: a
matrix_msgs/TrackArray on ``tracks_topic`` with that stamp. Done frames are announced on
``/graph_monitor/frame_done`` (std_msgs/Header with the frame's stamp), which a ``bag_player`` in lockstep
waits for, so no stage of the graph falls behind the replay.

When ``expected_frames`` frames are done, or nothing arrived for ``idle_timeout`` seconds, it prints the
summary table (also ``out_dir/graph_summary.txt``), writes ``out_dir/graph_overview.png`` and
``out_dir/graph_scores.csv``, and exits.
With the references register uses (``reference_dataset`` or ``site_references``) the registration is also
scored in reference pixels: against the true camera of the reference frame where the site file names that
frame's stamp (``site init``) and the recording's ground truth has it, else against the reference calibration.
Exit code 1 if no frame could be scored at all.
"""

import time

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import HomographyStamped, TrackArray
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

from matrix_bringup.monitor_settings import GraphMonitorSettings
from matrix_core import topics
from matrix_core.datasets.base import DatasetError
from matrix_core.datasets.drone_inputs import open_references
from matrix_core.evaluation.graph_report import true_references, write_graph_report
from matrix_core.message_fields import (
    ConversionError,
    camera_from_camera_info,
    image_from_msg,
    registration_from_msg,
    stamp_seconds,
)
from matrix_core.site.parameter import named_site
from matrix_ros.executor import make_executor, spin_until
from matrix_ros.params import SettingsNode, declare_settings, parse_node_args
from matrix_ros.qos import publisher_qos, qos_by_name


class GraphMonitor(SettingsNode):
    def __init__(self, defaults: GraphMonitorSettings):
        super().__init__('graph_monitor')
        self.settings = s = declare_settings(self, GraphMonitorSettings, defaults)
        self.truth, self.estimated, self.homography, self.images = {}, {}, {}, {}
        self.last_arrival = time.monotonic()
        self.done = False
        self.references = self._references()
        self.reference_stamps = self._reference_stamps()
        history = qos_by_name('history', depth=50)
        for view in s.views:
            self.create_subscription(
                CameraInfo,
                topics.drone_topic(view, topics.GROUND_TRUTH_CAMERA_INFO),
                lambda m, v=view: self._camera(self.truth, v, m),
                history,
            )
            self.create_subscription(
                CameraInfo,
                topics.drone_topic(view, topics.CAMERA_INFO),
                lambda m, v=view: self._camera(self.estimated, v, m),
                history,
            )
            self.create_subscription(
                HomographyStamped,
                topics.drone_topic(view, topics.HOMOGRAPHY),
                lambda m, v=view: self._homography(v, m),
                history,
            )
            self.create_subscription(
                Image,
                topics.drone_topic(view, topics.IMAGE_RAW),
                lambda m, v=view: self._image(v, m),
                qos_by_name('reliable', depth=2),
            )
        self.create_subscription(
            DiagnosticArray, topics.DIAGNOSTICS_TOPIC, self._diagnostics, qos_by_name('history', 200)
        )
        if 'tracks' in s.wait_for:
            self.create_subscription(TrackArray, s.tracks_topic, self._tracks, history)
        self.frame_done_pub = self.create_publisher(Header, topics.FRAME_DONE_TOPIC, publisher_qos())
        self.processed = {}  # stamp -> {(stage, view)} seen; view '' for tracks
        self.needed = {(stage, v) for stage in s.wait_for if stage != 'tracks' for v in s.views}
        self.needed |= {('tracks', '')} if 'tracks' in s.wait_for else set()
        self.announced = set()
        self.first_seen = {}  # stamp -> monotonic time of the frame's first message (any topic)
        self.warned = set()  # stamps warned about (waiting_warning)
        self.create_timer(0.5, self._check)

    def _references(self) -> dict:
        """view -> reference Camera register uses (its pixel error is scored against it); {} without a source.
        A view whose reference calibration cannot be read is said and scored in ground metres only."""
        s = self.settings
        try:
            dataset = open_references(s.reference_dataset, named_site(s.site) if s.site_references else None)
        except DatasetError as exc:
            self.get_logger().error(f'no registration pixel error: {exc}')
            return {}
        cameras = {}
        for view in [] if dataset is None else s.views:
            try:
                cameras[view] = dataset.reference_camera(view)
            except (DatasetError, OSError, ValueError) as exc:
                self.get_logger().error(f'{view}: no registration pixel error: unreadable reference calibration: {exc}')
        return cameras

    def _reference_stamps(self) -> dict:
        """view -> stamp (seconds) of the recorded frame its site reference was taken from; {} without one."""
        s = self.settings
        if not s.site_references:
            return {}
        site = named_site(s.site)
        drones = {d.name: d for d in site.drones}
        return {
            v: drones[v].reference.stamp_s
            for v in s.views
            if v in drones and drones[v].reference is not None and drones[v].reference.stamp_s is not None
        }

    def _key(self, view, msg):
        self.last_arrival = time.monotonic()
        stamp = round(stamp_seconds(msg.header.stamp), 6)
        self.first_seen.setdefault(stamp, self.last_arrival)
        return view, stamp

    def _processed(self, stage: str, view: str, header) -> None:
        """Note that ``stage`` processed ``view``'s frame at ``header.stamp``; announce the frame once done."""
        self.last_arrival = time.monotonic()
        stamp = round(stamp_seconds(header.stamp), 6)
        self.first_seen.setdefault(stamp, self.last_arrival)
        seen = self.processed.setdefault(stamp, set())
        seen.add((stage, view))
        if stamp not in self.announced and self.needed <= seen:
            self.announced.add(stamp)
            self.frame_done_pub.publish(Header(stamp=header.stamp))

    def _diagnostics(self, msg):
        for status in msg.status:
            stage, _, view = status.name.partition('/')
            if stage in ('register', 'calib') and view in self.settings.views:
                self._processed(stage, view, msg.header)

    def _tracks(self, msg):
        self._processed('tracks', '', msg.header)

    def _camera(self, store, view, msg):
        try:
            store[self._key(view, msg)] = camera_from_camera_info(msg)
        except ConversionError as exc:
            self.get_logger().error(f'{view}: unusable CameraInfo: {exc}')

    def _homography(self, view, msg):
        self.homography[self._key(view, msg)] = registration_from_msg(msg)

    def _image(self, view, msg):
        try:
            self.images[self._key(view, msg)] = image_from_msg(msg)
        except ConversionError as exc:
            self.get_logger().error(f'{view}: unusable image: {exc}')

    def _check(self):
        s = self.settings
        quiet = time.monotonic() - self.last_arrival
        self._warn_waiting()
        # Calibration publishes nothing for a drone without a good pose yet: once every frame's
        # homographies are in, a short quiet period means nothing more is coming.
        if s.expected_frames and len(self.announced) >= s.expected_frames and quiet > s.settle_time:
            self.get_logger().info(f'{s.expected_frames} frames done ({", ".join(s.wait_for)})')
            self.finish()
        elif quiet > s.idle_timeout:
            self.get_logger().info(f'nothing arrived for {s.idle_timeout:.0f} s')
            self.finish()

    def missing(self, stamp: float) -> list:
        """'stage/view' (or 'tracks') of every part frame ``stamp`` still waits for, sorted."""
        seen = self.processed.get(stamp, set())
        return sorted(f'{stage}/{view}' if view else stage for stage, view in self.needed - seen)

    def _warn_waiting(self) -> None:
        """Name, once, what a frame not done ``waiting_warning`` seconds after its first message waits for."""
        now = time.monotonic()
        for stamp, first in sorted(self.first_seen.items()):
            if stamp in self.announced or stamp in self.warned or now - first < self.settings.waiting_warning:
                continue
            self.warned.add(stamp)
            self.get_logger().warning(
                f'frame t={stamp:.3f} s not done {now - first:.0f} s after its first '
                f'message; waiting for {", ".join(self.missing(stamp))}'
            )

    def finish(self):
        s = self.settings
        references, true_views = true_references(self.references, self.reference_stamps, self.truth)
        if true_views:
            self.get_logger().info(
                f'registration scored against the true camera of the reference frame: {", ".join(true_views)}'
            )
        self.scored = write_graph_report(
            s.out_dir, s.views, s.area, self.truth, self.estimated, self.homography, self.images, references
        )
        self.done = True


def main(argv=None) -> int:
    cli, argv = parse_node_args(GraphMonitorSettings, argv, __doc__)
    rclpy.init(args=argv)
    node, executor = GraphMonitor(cli), make_executor()
    executor.add_node(node)
    try:
        spin_until(executor, lambda: node.done, 0.2)
    except KeyboardInterrupt:
        pass
    if not node.done:  # stopped by SIGINT or SIGTERM (rclpy's handlers): report what was seen
        node.finish()
    scored = getattr(node, 'scored', 0)
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()
    return 0 if scored else 1


if __name__ == '__main__':
    raise SystemExit(main())
