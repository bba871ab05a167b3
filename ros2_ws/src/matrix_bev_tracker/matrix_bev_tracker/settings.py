"""Parameters of the ``fuse`` node: the fusion settings (``matrix_core.fusion.settings``, incl. the tracker's)
plus the node's outputs."""

from dataclasses import dataclass, field

from matrix_core import topics
from matrix_core.fusion.settings import FuseSettings
from matrix_ros.node_settings import NodeSettings


@dataclass
class FuseNodeSettings(NodeSettings, FuseSettings):
    tracks_topic: str = field(default=topics.TRACKS, metadata={'help': 'matrix_msgs/TrackArray of the tracks'})
    detections_topic: str = field(default=topics.DETECTIONS, metadata={
        'help': 'matrix_msgs/TrackArray of the detections (id 0)'})
    markers_topic: str = field(default=topics.MARKERS, metadata={'help': 'visualization_msgs/MarkerArray of the tracks'})
    heatmap_topic: str = field(default=topics.BEV_HEATMAP, metadata={
        'help': 'nav_msgs/OccupancyGrid heatmap ("" = off)'})
    world_frame: str = field(default=topics.WORLD_FRAME, metadata={'help': 'frame_id of everything published'})
    stamp_tolerance: float = field(default=0.001, metadata={'help': 'stamps closer than this (s) are one frame'})
    jpeg_reduced_decode: bool = field(default=True, metadata={
        'help': 'decode JPEG images directly at 1/2, 1/4 or 1/8 size when that still covers the network input '
                '(1920x1080 -> 960x540 for 480x272): about 0.1 s less per frame of 8 views; pixels differ from a '
                'full decode + resize by < 1 grey level'})


# What `ros2 param set /fuse NAME VALUE` may change while the node runs (the node reads them each frame);
# the others are read-only: they shape the network, the tracker or the subscriptions, fixed at start.
LIVE_PARAMETERS = ('tracker_reset_gap_s', 'world_frame')
