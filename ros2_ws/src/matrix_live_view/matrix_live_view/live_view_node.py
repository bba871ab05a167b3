"""``live_view``: the graph as Foxglove or Lichtblick show it, over the Foxglove WebSocket protocol (ws://HOST:PORT).

Subscribes ``tracks`` (matrix_msgs/TrackArray), ``bev_heatmap`` (OccupancyGrid), ``/tf`` and ``/tf_static``
(calib's cameras, fuse's fixed frames) and per drone ``V`` in ``views`` ``V/camera_info`` and
``V/overlay/compressed`` (fuse's ``overlay``); the images best effort, so that a busy live view never holds
up their publisher. Serves (``matrix_live_view.server``; messages: ``foxglove_messages``):

    /live_view/scene    SceneUpdate       the area's outline, the obstacles, each camera's frustum (its frame)
    /live_view/tracks   SceneUpdate       per track a cylinder, its id and its trail (``trail_frames``)
    /bev_heatmap        Grid              the heatmap (int8 0-100, -1 where no view was usable)
    /tf, /tf_static     FrameTransforms   world -> Dn/camera_optical, world -> area
    /V/camera_info      CameraCalibration
    /V/overlay/compressed  CompressedImage  the drone's image with the tracks' boxes and ids

the names of the ROS topics they come from (a recording opens in the same layout, docs/live-view.md). What
no client subscribed is not built; a slow client loses its oldest messages (``client_backlog``); the scene,
the static frames and the frustums go out again with every tracks message, for clients that join late.
"""

from nav_msgs.msg import OccupancyGrid
from matrix_msgs.msg import TrackArray
from sensor_msgs.msg import CameraInfo, CompressedImage
from tf2_msgs.msg import TFMessage

from matrix_core import topics
from matrix_core.fusion.image_boxes import obstacles_from_meta
from matrix_core.geometry.occlusion import as_boxes
from matrix_core.live_scene import Trails
from matrix_live_view import foxglove_messages as fm
from matrix_live_view.server import LiveServer
from matrix_live_view.settings import LiveViewSettings
from matrix_core.message_fields import stamp_seconds
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import qos_by_name

SCENE, TRACKS = '/live_view/scene', '/live_view/tracks'


def channel_kinds(views) -> dict:
    """Every channel the live view serves for ``views``: topic -> kind (``matrix_live_view.server.CHANNELS``)."""
    return {
        SCENE: 'scene',
        TRACKS: 'scene',
        topics.graph_topic(topics.BEV_HEATMAP): 'grid',
        topics.TF_TOPIC: 'transforms',
        topics.TF_STATIC_TOPIC: 'transforms',
        **{topics.absolute(v, topics.CAMERA_INFO): 'calibration' for v in views},
        **{topics.absolute(v, topics.OVERLAY_COMPRESSED): 'image' for v in views},
    }


class LiveViewNode(SettingsNode):
    def __init__(self, defaults: LiveViewSettings):
        super().__init__('live_view')
        self.settings = s = declare_settings(self, LiveViewSettings, defaults)
        self.area, boxes = self._scene(s)
        self.boxes = as_boxes(boxes)
        self.trails, self.last_stamp = Trails(s.trail_frames), None
        self.frustums, self.cameras, self.static = {}, {}, {}  # by view; (parent, child) -> TransformStamped
        self.server = LiveServer(self.get_logger(), s.host, s.port, s.client_backlog)
        self.topics = channel_kinds(s.views)
        for topic, kind in self.topics.items():  # advertised now: a client lists them all at once
            self.server.channel(kind, topic)
        reliable = qos_by_name('reliable')
        self.create_subscription(TrackArray, topics.TRACKS, self._on_tracks, reliable)
        self.create_subscription(OccupancyGrid, topics.BEV_HEATMAP, self._on_heatmap, reliable)
        self.create_subscription(TFMessage, topics.TF_TOPIC, self._on_tf, qos_by_name('reliable', 100))
        self.create_subscription(TFMessage, topics.TF_STATIC_TOPIC, self._on_tf_static, qos_by_name('history'))
        for v in s.views:
            self.create_subscription(
                CameraInfo,
                topics.drone_topic(v, topics.CAMERA_INFO),
                lambda m, v=v: self._on_camera_info(v, m),
                reliable,
            )
            self.create_subscription(
                CompressedImage,
                topics.drone_topic(v, topics.OVERLAY_COMPRESSED),
                lambda m, v=v: self._send(
                    'image', topics.absolute(v, topics.OVERLAY_COMPRESSED), fm.compressed_image, m
                ),
                qos_by_name('sensor_data'),
            )
        self.get_logger().info(
            f'serving ws://{s.host}:{self.server.port} (Foxglove WebSocket protocol): {len(self.topics)} channels, '
            f'{len(s.views)} drones; open it in Foxglove or Lichtblick with share/matrix_live_view/config/'
            'foxglove_layout.json'
        )

    def _scene(self, s) -> tuple:
        """(area, obstacle boxes): a simulated scene_dataset's own (its meta), else the parameters'."""
        if not s.scene_dataset:
            return s.area, s.obstacle_boxes
        from matrix_core.datasets import DatasetError, MatrixDataset

        try:
            meta = getattr(MatrixDataset(s.scene_dataset), 'meta', None) or {}
        except DatasetError as exc:
            self.get_logger().error(f'scene_dataset: {exc}; drawing area and obstacle_boxes')
            return s.area, s.obstacle_boxes
        area = (meta.get('simulator') or {}).get('config', {}).get('area') or s.area
        return list(area), obstacles_from_meta(meta, s.obstacle_boxes)

    def _send(self, kind: str, topic: str, convert, msg) -> None:
        """``convert(msg)`` on ``topic`` if any client wants it; a message it cannot convert is logged, not fatal."""
        if not self.server.wanted(kind, topic):
            return
        try:
            self.server.log(kind, topic, convert(msg))
        except (TypeError, ValueError, OverflowError) as exc:
            self.get_logger().error(f'{topic}: message not shown: {exc}', throttle_duration_sec=5.0)

    def _on_tracks(self, msg: TrackArray) -> None:
        stamp = stamp_seconds(msg.header.stamp)
        if self.last_stamp is not None and stamp < self.last_stamp:  # a replay restarted: old trails are wrong
            self.trails.reset()
        self.last_stamp = stamp
        trails = self.trails.update((t.id, (t.position.x, t.position.y)) for t in msg.tracks)
        self._send('scene', TRACKS, lambda m: fm.tracks_update(m, trails), msg)
        scene = fm.area_entities(msg.header.stamp, msg.header.frame_id or topics.WORLD_FRAME, self.area, self.boxes)
        self._send('scene', SCENE, lambda _: fm.SceneUpdate(entities=scene + list(self.frustums.values())), msg)
        if self.static:
            self._send(
                'transforms',
                topics.TF_STATIC_TOPIC,
                fm.frame_transforms,
                TFMessage(transforms=list(self.static.values())),
            )

    def _on_heatmap(self, msg: OccupancyGrid) -> None:
        self._send('grid', topics.graph_topic(topics.BEV_HEATMAP), fm.grid, msg)

    def _on_tf(self, msg: TFMessage) -> None:
        self._send('transforms', topics.TF_TOPIC, fm.frame_transforms, msg)

    def _on_tf_static(self, msg: TFMessage) -> None:
        for t in msg.transforms:
            self.static[(t.header.frame_id, t.child_frame_id)] = t
        self._send('transforms', topics.TF_STATIC_TOPIC, fm.frame_transforms, msg)

    def _on_camera_info(self, view: str, msg: CameraInfo) -> None:
        camera = (msg.header.frame_id, msg.width, msg.height, tuple(msg.k))  # the frustum changes with these only
        if self.cameras.get(view) != camera:
            try:
                self.frustums[view] = fm.frustum_entity(msg.header.stamp, view, msg, self.settings.frustum_depth_m)
                self.cameras[view] = camera
            except (ValueError, ArithmeticError) as exc:  # a singular K: no frustum for this camera
                self.get_logger().error(f'{view}: camera_info not drawn: {exc}', throttle_duration_sec=5.0)
        self._send('calibration', topics.absolute(view, topics.CAMERA_INFO), fm.calibration, msg)

    def close(self) -> None:
        self.server.stop()


def main(argv=None) -> int:
    return spin_node(LiveViewNode, LiveViewSettings, argv, description=__doc__, on_exit=LiveViewNode.close)


if __name__ == '__main__':
    raise SystemExit(main())
