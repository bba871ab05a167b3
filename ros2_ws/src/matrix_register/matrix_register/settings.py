"""Parameters of the ``register`` node: the registration settings (same names as ``matrix-tracker register``
flags) plus the node's wiring."""

from dataclasses import dataclass, field

from matrix_core import topics
from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.register.settings import RegisterSettings
from matrix_core.settings import check_area
from matrix_core.site.parameter import site_references_field
from matrix_ros.node_settings import NodeSettings


@dataclass
class RegisterNodeSettings(NodeSettings, RegisterSettings):
    views: list[str] = field(
        default_factory=list,
        metadata={
            'help': 'drones hosted by this process, topics <V>/... (relative; bare for the drone whose namespace the '
            'node runs in); empty = the one drone of the node namespace'
        },
    )
    reference_dataset: str = field(
        default='',
        metadata={
            'help': 'MATRIX folder whose reference/ holds each view\'s reference image and calibration; empty: '
            'the first frame with a CameraInfo becomes the reference'
        },
    )
    site_references: bool = site_references_field()
    area: list[float] = field(
        default_factory=lambda: list(MATRIX_AREA),
        metadata={
            'help': 'scene ground x_min y_min x_max y_max (internal world metres); overridden by reference_dataset'
        },
    )
    image_topic: str = field(default=topics.IMAGE_RAW, metadata={'help': 'image stream under <view>/'})
    compressed: bool = field(
        default=False, metadata={'help': 'subscribe <V>/image/compressed (JPEG) instead of the raw image'}
    )
    camera_info_topic: str = field(
        default=topics.CAMERA_INFO,
        metadata={'help': 'CameraInfo stream under <view>/ (used only without reference_dataset)'},
    )

    def check(self) -> None:
        check_area(self.area)
        if self.site_references and self.reference_dataset:
            raise ValueError('give reference_dataset or site_references, not both')
