"""Parameters of the ``register`` node: the registration settings (same names as ``matrix-tracker register``
flags) plus the node's wiring."""

from dataclasses import dataclass, field

from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.register.settings import RegisterSettings
from matrix_core.sync import RestartSettings
from matrix_ros.node_settings import NodeSettings


@dataclass
class RegisterNodeSettings(NodeSettings, RestartSettings, RegisterSettings):
    views: list[str] = field(
        default_factory=lambda: ['D1'],
        metadata={
            'help': 'drones handled by this node; topics are <view>/... (relative: remappable, namespaceable; bare '
            'for the drone whose namespace the node runs in; empty: that one drone)'
        },
    )
    reference_dataset: str = field(
        default='',
        metadata={
            'help': 'MATRIX folder whose reference/ holds each view\'s reference image and calibration; empty: '
            'the first frame with a CameraInfo becomes the reference'
        },
    )
    area: list[float] = field(
        default_factory=lambda: list(MATRIX_AREA),
        metadata={
            'help': 'scene ground x_min y_min x_max y_max (internal world metres); overridden by reference_dataset'
        },
    )
    image_topic: str = field(default='image_raw', metadata={'help': 'image stream under <view>/'})
    compressed: bool = field(default=False, metadata={'help': 'subscribe <view>/image/compressed instead'})
    camera_info_topic: str = field(
        default='camera_info',
        metadata={'help': 'CameraInfo stream under <view>/ (used only without reference_dataset)'},
    )

    def __post_init__(self):
        super().__post_init__()
        if len(self.area) != 4 or self.area[0] >= self.area[2] or self.area[1] >= self.area[3]:
            raise ValueError(f'area must be x_min y_min x_max y_max, got {self.area}')
