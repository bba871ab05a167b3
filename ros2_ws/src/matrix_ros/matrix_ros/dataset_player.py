"""``dataset_player``: publish a MATRIX/Wildtrack/MultiviewX folder as per-view ROS 2 topics.

Per view ``V`` (e.g. ``D1``) and frame, with header stamp ``start_time + frame_index * frame_period``:
``/V/image_raw`` (sensor_msgs/Image, bgr8) or ``/V/image/compressed`` (the file's own bytes, when
``compressed`` is true), and ``/V/ground_truth/camera_info`` (the dataset's stored calibration, see
``matrix_ros.conversions`` for the ``p = K [R | t]`` convention). Frame ids: ``V/camera_optical``.
"""

import time
from dataclasses import dataclass, field

from std_msgs.msg import Header
from sensor_msgs.msg import CameraInfo, CompressedImage, Image

from matrix_core import topics
from matrix_core.bags.clock import DEFAULT_CLOCK
from matrix_core.datasets import DatasetError, open_dataset
from matrix_ros.connect import SubscribersReady
from matrix_ros.conversions import camera_to_camera_info, image_to_msg, seconds_to_stamp
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name


@dataclass
class DatasetPlayerSettings:
    dataset: str = field(default='', metadata={'help': 'MATRIX, Wildtrack or MultiviewX folder to publish'})
    rate: float = field(default=1.0, metadata={'help': 'playback speed factor (1.0 = recorded 0.5 s period)'})
    frame_period: float = field(
        default=DEFAULT_CLOCK.frame_period, metadata={'help': 'seconds between recorded frames'}
    )
    start_time: float = field(
        default=DEFAULT_CLOCK.start_time, metadata={'help': 'header stamp of the first frame, seconds'}
    )
    views: list[str] = field(default_factory=list, metadata={'help': 'views to publish (empty = all)'})
    max_frames: int = field(default=0, metadata={'help': 'publish at most this many frames (0 = all)'})
    loop: bool = field(default=False, metadata={'help': 'start again after the last frame'})
    compressed: bool = field(default=False, metadata={'help': 'publish image/compressed instead of image_raw'})
    qos: str = field(default='reliable', metadata={'help': 'QoS of the image topics: reliable or sensor_data'})
    wait_for_subscribers: int = field(
        default=0, metadata={'help': 'wait until each image topic has this many subscribers before starting'}
    )

    def __post_init__(self):
        if self.rate <= 0 or self.frame_period <= 0:
            raise ValueError('rate and frame_period must be positive')
        qos_by_name(self.qos)


class DatasetPlayer(SettingsNode):
    def __init__(self, defaults: DatasetPlayerSettings):
        super().__init__('dataset_player')
        self.settings = s = declare_settings(self, DatasetPlayerSettings, defaults)
        self.dataset = open_dataset(s.dataset)
        self.frames = self.dataset.select_frames(s.max_frames)
        self.views = self.dataset.select_views(s.views)
        if not self.frames:
            raise DatasetError(f'{s.dataset} has no complete frame to publish')
        qos = publisher_qos(s.qos)
        self.image_pubs, self.info_pubs = {}, {}
        for view in self.views:
            self.image_pubs[view] = self.create_publisher(
                CompressedImage if s.compressed else Image, topics.image_topic(view, s.compressed), qos
            )
            self.info_pubs[view] = self.create_publisher(CameraInfo, topics.camera_info_topic(view), publisher_qos())
        self.subscribers = SubscribersReady(self.image_pubs, s.wait_for_subscribers)
        self.index = 0
        self.timer = self.create_timer(s.frame_period / s.rate, self._tick)
        self.get_logger().info(
            f'publishing {len(self.frames)} frames x {len(self.views)} views '
            f'of {s.dataset} at {1.0 / s.frame_period * s.rate:.2f} Hz'
        )

    def _ready(self) -> bool:
        return self.subscribers.ready(time.monotonic())

    def _tick(self):
        if not self._ready():
            return
        if self.index >= len(self.frames):
            if not self.settings.loop:
                self.get_logger().info('all frames published')
                self.timer.cancel()
                return
            self.index = 0
        frame = self.frames[self.index]
        stamp = seconds_to_stamp(self.settings.start_time + self.index * self.settings.frame_period)
        for view in self.views:
            header = Header(stamp=stamp, frame_id=topics.optical_frame(view))
            try:
                self.image_pubs[view].publish(self._image_msg(view, frame, header))
                self.info_pubs[view].publish(camera_to_camera_info(self.dataset.camera(view, frame), header))
            except DatasetError as exc:
                self.get_logger().error(f'frame {frame} view {view} not published: {exc}')
        self.index += 1

    def _image_msg(self, view, frame, header):
        if self.settings.compressed:
            path = self.dataset.image_path(view, frame)
            msg = CompressedImage(header=header, format=path.suffix.lstrip('.').replace('jpg', 'jpeg'))
            msg.data = path.read_bytes()
            return msg
        return image_to_msg(self.dataset.load_image(view, frame), header)


def main(argv=None) -> int:
    return spin_node(DatasetPlayer, DatasetPlayerSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
