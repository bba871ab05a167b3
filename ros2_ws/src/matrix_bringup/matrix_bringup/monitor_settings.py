"""Parameters of the ``graph_monitor`` node."""

from dataclasses import dataclass, field

from matrix_core.settings import check_area

from matrix_core import topics
from matrix_core.site.parameter import site_field, site_references_field
from matrix_core.datasets.matrix_conventions import MATRIX_AREA, MATRIX_VIEWS

STAGES = ('register', 'calib', 'tracks')


@dataclass
class GraphMonitorSettings:
    views: list[str] = field(default_factory=lambda: list(MATRIX_VIEWS), metadata={'help': 'views to score'})
    expected_frames: int = field(
        default=0, metadata={'help': 'stop after this many frames are done (0 = on idle_timeout only)'}
    )
    wait_for: list[str] = field(
        default_factory=lambda: ['register'],
        metadata={'help': f'stages that must have processed a frame before it is done (announced): any of {STAGES}'},
    )
    tracks_topic: str = field(
        default=topics.TRACKS, metadata={'help': 'matrix_msgs/TrackArray topic of the tracks stage'}
    )
    settle_time: float = field(
        default=3.0,
        metadata={'help': 'after expected_frames are done, stop once nothing arrived for this long, seconds'},
    )
    waiting_warning: float = field(
        default=10.0,
        metadata={
            'help': 'warn once about a frame still not done this many seconds after its first message, naming the '
            'stages and views it waits for, seconds'
        },
    )
    idle_timeout: float = field(default=30.0, metadata={'help': 'stop when nothing arrived for this long, seconds'})
    area: list[float] = field(
        default_factory=lambda: list(MATRIX_AREA),
        metadata={'help': 'scene ground x_min y_min x_max y_max (internal world metres) for the scores and picture'},
    )
    out_dir: str = field(default='out/graph_monitor', metadata={'help': 'where the table, CSV and PNG go'})
    reference_dataset: str = field(
        default='',
        metadata={
            'help': "the dataset folder whose reference calibrations register uses: with it (or site_references) the "
            "registration is also scored in reference pixels; empty: ground metres only"
        },
    )
    site: str = site_field()
    site_references: bool = site_references_field()

    def __post_init__(self):
        unknown = set(self.wait_for) - set(STAGES)
        if unknown or not self.wait_for:
            raise ValueError(f'wait_for must list some of {STAGES}, got {self.wait_for}')
        check_area(self.area)
        if self.site_references and self.reference_dataset:
            raise ValueError('give reference_dataset or site_references, not both')
