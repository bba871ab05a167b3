"""Parameters of the ``calib`` node: the calibration settings (same names as ``matrix-tracker calibrate``
flags) plus the node's wiring."""

from dataclasses import dataclass, field

from matrix_core.calib.settings import CalibSettings
from matrix_core.site.parameter import site_references_field
from matrix_core.topics import WORLD_FRAME
from matrix_ros.node_settings import NodeSettings


@dataclass
class CalibNodeSettings(NodeSettings, CalibSettings):
    views: list[str] = field(
        default_factory=list,
        metadata={
            'help': 'drones hosted by this process, topics <V>/... (relative; bare for the drone whose namespace the '
            'node runs in); empty = the one drone of the node namespace'
        },
    )
    compressed: bool = field(
        default=False, metadata={'help': 'subscribe <V>/image/compressed (JPEG) instead of the raw image'}
    )
    world_frame: str = field(default=WORLD_FRAME, metadata={'help': 'frame_id of the published pose'})
    publish_stale: bool = field(
        default=True,
        metadata={'help': 'republish the last good pose (stamped with the new image) when this image gave none'},
    )
    intrinsics_topic: str = field(
        default='',
        metadata={
            'help': 'per-drone CameraInfo stream (relative to V/, e.g. ground_truth/camera_info) whose k, d and '
            'size replace the config intrinsics; its extrinsics are ignored; empty = config only'
        },
    )
    use_registration: bool = field(
        default=False,
        metadata={
            'help': "pair each image with the drone's registration of the same stamp (V/homography, "
            'matrix_msgs/HomographyStamped from register) and let the camera it implies guide the calibration '
            '(track_registered: about 0.1 s instead of 0.5 s per 1080p frame); images are subscribed once that '
            'stream has a publisher'
        },
    )
    registration_wait_s: float = field(
        default=3.0,
        metadata={
            'help': 'with use_registration: seconds (wall clock) an image waits for its registration before it is '
            'calibrated from the image motion instead (logged)'
        },
    )
    thread_niceness: int = field(
        default=5,
        metadata={
            'help': 'in one process with register (matrix_bringup.drone): calib runs on a thread of its own, this much '
            'nicer than register\'s (at most 19 in all), so that on a computer shared by several drones the '
            'registrations fuse waits for go first; -1 = on register\'s thread (matrix_ros.drone_link)'
        },
    )
    prior_dataset: str = field(
        default='',
        metadata={
            'help': 'MATRIX folder whose reference/calibrations (and reference images) give the first prior; '
            'empty = the config\'s initial_poses'
        },
    )

    site_references: bool = site_references_field()

    def check(self) -> None:
        if self.site_references and self.prior_dataset:
            raise ValueError('give prior_dataset or site_references, not both')
        if self.registration_wait_s <= 0:
            raise ValueError('registration_wait_s must be positive')
        if self.thread_niceness < -1:
            raise ValueError(f'thread_niceness must be >= -1 (-1: no thread of its own), got {self.thread_niceness}')
