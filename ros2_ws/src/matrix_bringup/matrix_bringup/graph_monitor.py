"""``graph_monitor``: score what the running graph publishes against the ground truth, then exit.

Per view ``V`` it subscribes ``/V/camera_info`` (from ``calib``), ``/V/homography`` (from ``register``),
``/V/ground_truth/camera_info`` and ``/V/image_raw`` (from the player). When ``expected_frames`` frames
have arrived complete for every view, or nothing arrived for ``idle_timeout`` seconds, it prints the
summary table, writes ``out_dir/graph_overview.png`` and ``out_dir/graph_scores.csv``, and exits.
Each frame for which every view's homography arrived is announced on ``/graph_monitor/frame_done``
(std_msgs/Header with the frame's stamp), which a ``bag_player`` in lockstep waits for.
Exit code 1 if no frame could be scored at all.
"""

import csv
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import cv2
import numpy as np
import rclpy
from matrix_msgs.msg import HomographyStamped
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image
from std_msgs.msg import Header

from matrix_core.evaluation.graph_report import overview_image, score_view_frame, summary_table
from matrix_ros.conversions import ConversionError, camera_info_to_camera, msg_to_image, stamp_to_seconds
from matrix_ros.params import parse_node_args, declare_settings
from matrix_ros.qos import qos_by_name


@dataclass
class GraphMonitorSettings:
    views: list[str] = field(default_factory=lambda: [f'D{i}' for i in range(1, 9)],
                             metadata={'help': 'views to score'})
    expected_frames: int = field(default=0, metadata={
        'help': 'stop after this many frames were registered by every view (0 = on idle_timeout only)'})
    settle_time: float = field(default=3.0, metadata={
        'help': 'after expected_frames were registered, stop once nothing arrived for this long, seconds'})
    idle_timeout: float = field(default=30.0, metadata={'help': 'stop when nothing arrived for this long, seconds'})
    area: list[float] = field(default_factory=lambda: [0.0, -30.0, 30.0, 0.0], metadata={
        'help': 'scene ground x_min y_min x_max y_max (internal world metres) for the scores and picture'})
    out_dir: str = field(default='out/graph_monitor', metadata={'help': 'where the table, CSV and PNG go'})

    def __post_init__(self):
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')


class GraphMonitor(Node):
    def __init__(self, defaults: GraphMonitorSettings):
        super().__init__('graph_monitor')
        self.settings = s = declare_settings(self, GraphMonitorSettings, defaults)
        self.truth, self.estimated, self.homography, self.images = {}, {}, {}, {}
        self.last_arrival = time.monotonic()
        self.done = False
        for view in s.views:
            self.create_subscription(CameraInfo, f'/{view}/ground_truth/camera_info',
                                     lambda m, v=view: self._camera(self.truth, v, m), 50)
            self.create_subscription(CameraInfo, f'/{view}/camera_info',
                                     lambda m, v=view: self._camera(self.estimated, v, m), 50)
            self.create_subscription(HomographyStamped, f'/{view}/homography',
                                     lambda m, v=view: self._homography(v, m), 50)
            self.create_subscription(Image, f'/{view}/image_raw', lambda m, v=view: self._image(v, m),
                                     qos_by_name('reliable', depth=2))
        self.frame_done_pub = self.create_publisher(Header, '/graph_monitor/frame_done', 10)
        self.announced = set()
        self.create_timer(0.5, self._check)

    def _key(self, view, msg):
        self.last_arrival = time.monotonic()
        return view, round(stamp_to_seconds(msg.header.stamp), 6)

    def _camera(self, store, view, msg):
        try:
            store[self._key(view, msg)] = camera_info_to_camera(msg)
        except ConversionError as exc:
            self.get_logger().error(f'{view}: unusable CameraInfo: {exc}')

    def _homography(self, view, msg):
        key = self._key(view, msg)
        self.homography[key] = msg
        stamp = key[1]
        if stamp not in self.announced and all((v, stamp) in self.homography for v in self.settings.views):
            self.announced.add(stamp)
            self.frame_done_pub.publish(msg.header)

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
            self.get_logger().info(f'{s.expected_frames} frames registered by every view')
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
        print(summary_table(scores, s.views), flush=True)
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
