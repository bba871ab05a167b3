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
Exit code 1 if no frame could be scored at all.
"""

import csv
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import HomographyStamped, TrackArray
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.evaluation.graph_report import overview_image, score_view_frame, summary_table
from matrix_ros.conversions import ConversionError, camera_info_to_camera, msg_to_image, stamp_to_seconds
from matrix_ros.params import parse_node_args, declare_settings
from matrix_ros.qos import publisher_qos, qos_by_name

STAGES = ('register', 'calib', 'tracks')


@dataclass
class GraphMonitorSettings:
    views: list[str] = field(default_factory=lambda: [f'D{i}' for i in range(1, 9)],
                             metadata={'help': 'views to score'})
    expected_frames: int = field(default=0, metadata={
        'help': 'stop after this many frames are done (0 = on idle_timeout only)'})
    wait_for: list[str] = field(default_factory=lambda: ['register'], metadata={
        'help': f'stages that must have processed a frame before it is done (announced): any of {STAGES}'})
    tracks_topic: str = field(default='/tracks', metadata={'help': 'matrix_msgs/TrackArray topic of the tracks stage'})
    settle_time: float = field(default=3.0, metadata={
        'help': 'after expected_frames are done, stop once nothing arrived for this long, seconds'})
    idle_timeout: float = field(default=30.0, metadata={'help': 'stop when nothing arrived for this long, seconds'})
    area: list[float] = field(default_factory=lambda: list(MATRIX_AREA), metadata={
        'help': 'scene ground x_min y_min x_max y_max (internal world metres) for the scores and picture'})
    out_dir: str = field(default='out/graph_monitor', metadata={'help': 'where the table, CSV and PNG go'})

    def __post_init__(self):
        unknown = set(self.wait_for) - set(STAGES)
        if unknown or not self.wait_for:
            raise ValueError(f'wait_for must list some of {STAGES}, got {self.wait_for}')
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')


class GraphMonitor(Node):
    def __init__(self, defaults: GraphMonitorSettings):
        super().__init__('graph_monitor')
        self.settings = s = declare_settings(self, GraphMonitorSettings, defaults)
        self.truth, self.estimated, self.homography, self.images = {}, {}, {}, {}
        self.last_arrival = time.monotonic()
        self.done = False
        history = qos_by_name('history', depth=50)
        for view in s.views:
            self.create_subscription(CameraInfo, f'/{view}/ground_truth/camera_info',
                                     lambda m, v=view: self._camera(self.truth, v, m), history)
            self.create_subscription(CameraInfo, f'/{view}/camera_info',
                                     lambda m, v=view: self._camera(self.estimated, v, m), history)
            self.create_subscription(HomographyStamped, f'/{view}/homography',
                                     lambda m, v=view: self._homography(v, m), history)
            self.create_subscription(Image, f'/{view}/image_raw', lambda m, v=view: self._image(v, m),
                                     qos_by_name('reliable', depth=2))
        self.create_subscription(DiagnosticArray, '/diagnostics', self._diagnostics, qos_by_name('history', 200))
        if 'tracks' in s.wait_for:
            self.create_subscription(TrackArray, s.tracks_topic, self._tracks, history)
        self.frame_done_pub = self.create_publisher(Header, '/graph_monitor/frame_done', publisher_qos())
        self.processed = {}   # stamp -> {(stage, view)} seen; view '' for tracks
        self.needed = {(stage, v) for stage in s.wait_for if stage != 'tracks' for v in s.views}
        self.needed |= {('tracks', '')} if 'tracks' in s.wait_for else set()
        self.announced = set()
        self.create_timer(0.5, self._check)

    def _key(self, view, msg):
        self.last_arrival = time.monotonic()
        return view, round(stamp_to_seconds(msg.header.stamp), 6)

    def _processed(self, stage: str, view: str, header) -> None:
        """Note that ``stage`` processed ``view``'s frame at ``header.stamp``; announce the frame once done."""
        self.last_arrival = time.monotonic()
        stamp = round(stamp_to_seconds(header.stamp), 6)
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
            store[self._key(view, msg)] = camera_info_to_camera(msg)
        except ConversionError as exc:
            self.get_logger().error(f'{view}: unusable CameraInfo: {exc}')

    def _homography(self, view, msg):
        self.homography[self._key(view, msg)] = msg

    def _image(self, view, msg):
        try:
            self.images[self._key(view, msg)] = msg_to_image(msg)
        except ConversionError as exc:
            self.get_logger().error(f'{view}: unusable image: {exc}')

    def _check(self):
        s = self.settings
        quiet = time.monotonic() - self.last_arrival
        # Calibration publishes nothing for a drone without a good pose yet: once every frame's
        # homographies are in, a short quiet period means nothing more is coming.
        if s.expected_frames and len(self.announced) >= s.expected_frames and quiet > s.settle_time:
            self.get_logger().info(f'{s.expected_frames} frames done ({", ".join(s.wait_for)})')
            self.finish()
        elif quiet > s.idle_timeout:
            self.get_logger().info(f'nothing arrived for {s.idle_timeout:.0f} s')
            self.finish()

    def finish(self):
        s = self.settings
        scores = []
        for key, truth in sorted(self.truth.items(), key=lambda kv: (kv[0][1], kv[0][0])):
            h = self.homography.get(key)
            ground_H_img = None if h is None else np.array(h.h_img_to_ground).reshape(3, 3)
            scores.append(score_view_frame(key[0], key[1], truth, s.area, self.estimated.get(key),
                                           None if h is None else h.status,
                                           None if h is None else h.confidence, ground_H_img))
        out = Path(s.out_dir)
        out.mkdir(parents=True, exist_ok=True)
        table = summary_table(scores, s.views)
        print(table, flush=True)
        (out / 'graph_summary.txt').write_text(table + '\n')
        if scores:
            with open(out / 'graph_scores.csv', 'w', newline='') as f:
                writer = csv.DictWriter(f, fieldnames=list(asdict(scores[0])))
                writer.writeheader()
                writer.writerows(asdict(sc) for sc in scores)
            last = max(k[1] for k in self.truth)
            keys = [(v, last) for v in s.views if (v, last) in self.images and (v, last) in self.truth]
            if keys:
                ok_h = {k[0]: np.array(self.homography[k].h_img_to_ground).reshape(3, 3) for k in keys
                        if k in self.homography and self.homography[k].status == 'ok'}
                picture = overview_image({k[0]: self.images[k] for k in keys}, {k[0]: self.truth[k] for k in keys},
                                         s.area, {k[0]: self.estimated[k] for k in keys if k in self.estimated}, ok_h)
                cv2.imwrite(str(out / 'graph_overview.png'), picture)
                print(f'picture: {out / "graph_overview.png"} (white: true calibration, green: published '
                      f'calibration, magenta: registration homography)', flush=True)
        self.done = True
        self.scored = len(scores)


def main(argv=None) -> int:
    cli, argv = parse_node_args(GraphMonitorSettings, argv, __doc__)
    rclpy.init(args=argv)
    node = GraphMonitor(cli)
    try:
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.2)
    except KeyboardInterrupt:
        node.finish()
    scored = getattr(node, 'scored', 0)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0 if scored else 1


if __name__ == '__main__':
    raise SystemExit(main())
