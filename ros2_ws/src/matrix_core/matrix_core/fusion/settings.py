"""Settings of live fusion (the ``fuse`` node's parameters): wiring, model, sync, resets, and the tracker's."""

from dataclasses import dataclass, field
from pathlib import Path

from matrix_core import topics
from matrix_core.datasets.matrix_conventions import MATRIX_AREA, MATRIX_VIEWS
from matrix_core.device import DeviceSettings
from matrix_core.settings import check_area
from matrix_core.site.shipped import matrix_site
from matrix_core.sync.stamp_restart import RestartSettings
from matrix_core.threads import ThreadSettings
from matrix_core.tracking.settings import TrackerSettings

MATRIX_CELL_M = matrix_site().cell_m
INPUT_KINDS = ('homography', 'camera_info')
IMAGE_KINDS = ('raw', 'compressed', 'both')


# The default detector (docs/detector.md): bev/configs/detector.yaml, seed 1, selected on validation.
DEFAULT_CHECKPOINT = 'detector_seed1.pt'


def shipped_checkpoint(name: str = DEFAULT_CHECKPOINT) -> Path:
    """A checkpoint shipped with the package (``matrix_core/bev/checkpoints/``), by default
    :data:`DEFAULT_CHECKPOINT`, the one checkpoint of the fuse node, the demo and the experiments' "ours"."""
    return Path(__file__).resolve().parent.parent / 'bev' / 'checkpoints' / name


def resolve_checkpoint(checkpoint: str) -> Path:
    """The checkpoint file a setting names: a path, or the bare file name of a checkpoint shipped with the
    package (``detector_tiny_seed0.pt``: no need to know where the package is installed); empty: the default."""
    if not checkpoint:
        return shipped_checkpoint()
    path = Path(checkpoint)
    if path.is_file() or path.parent != Path('.') or not shipped_checkpoint(checkpoint).is_file():
        return path
    return shipped_checkpoint(checkpoint)


@dataclass
class FuseSettings(DeviceSettings, RestartSettings, TrackerSettings, ThreadSettings):
    """Everything the fusion of N views needs. Seconds, metres. ``frame_interval_s`` (from the tracker
    settings) is the frame period of the streams; ``device`` (``matrix_core.device``) where the network runs."""

    views: list[str] = field(
        default_factory=lambda: list(MATRIX_VIEWS),
        metadata={'help': 'drones to fuse, in the order the network sees them'},
    )
    image_kind: str = field(
        default='raw',
        metadata={
            'help': 'raw (sensor_msgs/Image on image_topic), compressed (CompressedImage on compressed_topic) or both'
        },
    )
    image_topic: str = field(
        default='{view}/' + topics.IMAGE_RAW,
        metadata={'help': 'raw image topic pattern ({view}: the drone; relative names, see matrix_core.topics)'},
    )
    compressed_topic: str = field(
        default='{view}/' + topics.IMAGE_COMPRESSED, metadata={'help': 'compressed image topic pattern'}
    )
    input_kind: str = field(
        default='homography',
        metadata={
            'help': 'where each frame\'s ground homography comes from: homography (matrix_msgs/HomographyStamped, '
            'h_img_to_ground, from register) or camera_info (CameraInfo p = K[R|t], from calib or the bag\'s '
            'ground truth)'
        },
    )
    dropped_topic: str = field(
        default='',
        metadata={
            'help': "pattern of a drone's notices of frames it did not send (std_msgs/Header; link_sender's "
            "'{view}/" + topics.LINK_DROPPED + "'): the frame does not wait for that image; empty: none"
        },
    )
    homography_topic: str = field(
        default='{view}/' + topics.HOMOGRAPHY, metadata={'help': 'HomographyStamped topic pattern'}
    )
    camera_info_topic: str = field(
        default='{view}/' + topics.CAMERA_INFO, metadata={'help': 'CameraInfo topic pattern'}
    )
    min_confidence: float = field(
        default=0.0, metadata={'help': 'homographies with a lower registration confidence are treated as missing'}
    )
    checkpoint: str = field(
        default='',
        metadata={
            'help': 'BEV model checkpoint (.pt): a path or the name of one shipped in matrix_core/bev/checkpoints '
            '(e.g. detector_tiny_seed0.pt, the faster detector); empty: the shipped default detector_seed1.pt'
        },
    )
    area: list[float] = field(
        default_factory=lambda: list(MATRIX_AREA),
        metadata={
            'help': 'scene x_min y_min x_max y_max (m): the BEV grid covers it (plus the checkpoint\'s margin); the '
            'network is convolutional over the grid, so any area runs'
        },
    )
    cell_m: float = field(
        default=MATRIX_CELL_M,
        metadata={
            'help': 'BEV cell (m) of the scene: must be the checkpoint\'s (the detector learnt people\'s size in its '
            'cells); a site with another cell needs a detector trained for it'
        },
    )
    score_threshold: float = field(
        default=-1.0, metadata={'help': 'heatmap peak threshold; negative: the checkpoint\'s'}
    )
    nms_radius_m: float = field(default=-1.0, metadata={'help': 'NMS radius (m); negative: the checkpoint\'s'})
    sync_timeout: float = field(
        default=1.0,
        metadata={
            'help': 'seconds to wait for missing views after a frame\'s first message (a stopped drone never stalls)'
        },
    )
    temporal_reset_gap_s: float = field(
        default=0.75,
        metadata={'help': 'forget the previous BEV features when frames are further apart than this (a lost frame)'},
    )
    tracker_reset_gap_s: float = field(
        default=5.0,
        metadata={'help': 'reset the tracker (ids restart) when frames are further apart than this (forward)'},
    )

    def check(self) -> None:
        if not self.views or len(set(self.views)) != len(self.views):
            raise ValueError(f'views must name distinct drones, got {self.views}')
        if self.image_kind not in IMAGE_KINDS:
            raise ValueError(f'image_kind must be one of {IMAGE_KINDS}, got {self.image_kind!r}')
        if self.input_kind not in INPUT_KINDS:
            raise ValueError(f'input_kind must be one of {INPUT_KINDS}, got {self.input_kind!r}')
        for name in ('image_topic', 'compressed_topic', 'homography_topic', 'camera_info_topic', 'dropped_topic'):
            if '{view}' not in getattr(self, name) and (getattr(self, name) or name != 'dropped_topic'):
                raise ValueError(f'{name} must contain {{view}}, got {getattr(self, name)!r}')
        check_area(self.area)
        if not self.cell_m > 0:
            raise ValueError(f'cell_m must be positive, got {self.cell_m}')
        if self.sync_timeout < 0 or self.temporal_reset_gap_s <= 0 or self.tracker_reset_gap_s <= 0:
            raise ValueError('sync_timeout >= 0 and the reset gaps > 0 are required')

    def topic(self, pattern: str, view: str) -> str:
        """A pattern's topic for ``view``: '{view}/image_raw' -> 'D3/image_raw' (= topics.drone_topic)."""
        return pattern.format(view=view)

    def checkpoint_path(self) -> Path:
        return resolve_checkpoint(self.checkpoint)

    def tracker_settings(self) -> TrackerSettings:
        return TrackerSettings(**{name: getattr(self, name) for name in TrackerSettings.__dataclass_fields__})

    def decode_overrides(self) -> dict:
        """Decoding settings that replace the checkpoint's (only those set >= 0)."""
        return {
            k: v for k, v in (('score_threshold', self.score_threshold), ('nms_radius_m', self.nms_radius_m)) if v >= 0
        }
