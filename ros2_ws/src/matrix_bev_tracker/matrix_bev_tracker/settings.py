"""Parameters of the ``fuse`` node: the fusion settings (``matrix_core.fusion.settings``, incl. the tracker's),
the image boxes' person model (``matrix_core.fusion.image_boxes``) plus the node's outputs."""

from dataclasses import dataclass, field

from matrix_core import topics
from matrix_core.fusion.image_boxes import ImageBoxSettings
from matrix_core.fusion.settings import FuseSettings
from matrix_core.site.parameter import site_references_field
from matrix_ros.node_settings import NodeSettings


GEOMETRY_QOS = ('history', 'reliable')  # never best effort: a lost homography loses the view's frame


@dataclass
class FuseNodeSettings(NodeSettings, ImageBoxSettings, FuseSettings):
    tracks_topic: str = field(default=topics.TRACKS, metadata={'help': 'matrix_msgs/TrackArray of the tracks'})
    detections_topic: str = field(
        default=topics.DETECTIONS, metadata={'help': 'matrix_msgs/TrackArray of the detections (id 0)'}
    )
    markers_topic: str = field(
        default=topics.MARKERS, metadata={'help': 'visualization_msgs/MarkerArray of the tracks'}
    )
    heatmap_topic: str = field(
        default=topics.BEV_HEATMAP, metadata={'help': 'nav_msgs/OccupancyGrid heatmap ("" = off)'}
    )
    detections_2d_topic: str = field(
        default='{view}/' + topics.DETECTIONS_2D,
        metadata={
            'help': 'matrix_msgs/Detection2DArray per drone: the tracks\' boxes in its image, with the fused ids '
            '(pattern; "" = off; see matrix_core.fusion.image_outputs for the camera of each view)'
        },
    )
    overlay: bool = field(
        default=False,
        metadata={
            'help': 'also publish each drone\'s image with the boxes and ids drawn on overlay_topic (JPEG; costs a '
            'full image decode and encode per view and frame)'
        },
    )
    overlay_topic: str = field(
        default='{view}/' + topics.OVERLAY_COMPRESSED,
        metadata={'help': 'sensor_msgs/CompressedImage overlay topic pattern'},
    )
    scene_dataset: str = field(
        default='',
        metadata={
            'help': 'MATRIX folder of the scene (the one the graph replays): its reference intrinsics give the camera '
            'a registration implies (input_kind homography), its meta the obstacles; "" = no 2D outputs '
            'from homographies'
        },
    )
    site_references: bool = site_references_field()
    geometry_qos: str = field(
        default='history',
        metadata={
            'help': 'QoS of the homography / camera_info subscriptions: history (transient local: also what a '
            'publisher sent before it matched this node; discovery is one-sided, so a drone may publish its '
            'first homography before it knows this node, though this node already knows the drone) or '
            'reliable (volatile; for publishers that offer only volatile durability)'
        },
    )
    world_frame: str = field(default=topics.WORLD_FRAME, metadata={'help': 'frame_id of everything published'})
    stamp_tolerance: float = field(default=0.001, metadata={'help': 'stamps closer than this (s) are one frame'})
    jpeg_reduced_decode: bool = field(
        default=True,
        metadata={
            'help': 'decode JPEG images directly at 1/2, 1/4 or 1/8 size when that still covers the network input '
            '(1920x1080 -> 960x540 for 480x272): about 0.1 s less per frame of 8 views; pixels differ from a '
            'full decode + resize by < 1 grey level'
        },
    )

    def check(self) -> None:
        if self.site_references and self.scene_dataset:
            raise ValueError('give scene_dataset or site_references, not both')
        if self.geometry_qos not in GEOMETRY_QOS:
            raise ValueError(f'geometry_qos must be one of {", ".join(GEOMETRY_QOS)}, got {self.geometry_qos!r}')


# What `ros2 param set /fuse NAME VALUE` may change while the node runs (the node reads them each frame);
# the others are read-only: they shape the network, the tracker or the subscriptions, fixed at start.
LIVE_PARAMETERS = ('tracker_reset_gap_s', 'world_frame')
