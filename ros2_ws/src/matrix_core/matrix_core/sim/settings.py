"""Settings of the simulator: the flags of ``matrix-tracker simulate`` (same names if it becomes a node)."""

from dataclasses import dataclass, field

from matrix_core.bags.clock import DEFAULT_CLOCK
from matrix_core.reference_size import REFERENCE_HEIGHT, REFERENCE_WIDTH
from matrix_core.site.shipped import MATRIX_SITE


@dataclass
class SimulateSettings:
    config: str = field(
        default='complex',
        metadata={'help': 'scene variant (simple, complex, modified) or the path of a YAML scene file'},
    )
    frames: int = field(default=10, metadata={'help': 'number of time steps to generate'})
    seed: int = field(
        default=0, metadata={'help': 'random seed: the same seed gives the same sequence (byte-identical annotations)'}
    )
    out: str = field(
        default='out/sim',
        metadata={'help': 'output folder (MATRIX format, or a site dataset with a site): new or empty'},
    )
    # The MATRIX site (the default) is simulated by the --config variants in the MATRIX format, as always;
    # any other site is rendered from its own file and written as a site dataset (docs/site-file.md).
    site: str = field(
        default=MATRIX_SITE,
        metadata={
            'help': 'site file (docs/site-file.md): a path or a shipped site (matrix, plaza). Default matrix: the '
            '--config variant in the MATRIX format; any other site: its area, drones, cameras, boards and '
            'obstacles, written as a site dataset (--config then gives the crowd, light and distractors)'
        },
    )
    image_scale: float = field(
        default=1.0,
        metadata={'help': 'with a site: render each drone at this fraction of its image size (intrinsics scaled)'},
    )
    ring_radius: float = field(
        default=0.0,
        metadata={
            'help': 'with a site: drones without a home or reference fly on a ring this far from the area centre, '
            'm (0: the area\'s half diagonal)'
        },
    )
    altitude: float = field(
        default=0.0,
        metadata={'help': 'with a site: flying height of drones without altitude_m or reference, m (0: the config\'s)'},
    )
    width: int = field(default=REFERENCE_WIDTH, metadata={'help': 'image width in pixels (the paper used 1920x1080)'})
    height: int = field(default=REFERENCE_HEIGHT, metadata={'help': 'image height in pixels'})
    fast: bool = field(default=False, metadata={'help': 'fast low-resolution mode: 640x360 (overrides width/height)'})
    image_ext: str = field(default='.png', metadata={'help': '.png (lossless) or .jpg (smaller, faster)'})
    bag: bool = field(default=False, metadata={'help': 'also write a rosbag2 (MCAP) into OUT/bag'})
    compressed: bool = field(
        default=False,
        metadata={'help': 'bag images as sensor_msgs/CompressedImage (JPEG) instead of sensor_msgs/Image'},
    )
    replay: str = field(
        default='', metadata={'help': 'MATRIX folder whose matchings/Pedestrians trajectories replace the crowd model'}
    )
    frame_period: float = field(default=DEFAULT_CLOCK.frame_period, metadata={'help': 'seconds between frames'})
    start_time: float = field(
        default=DEFAULT_CLOCK.start_time, metadata={'help': 'bag header stamp of the first frame, seconds'}
    )

    @property
    def site_dataset(self) -> bool:
        """Whether this run renders a site file into a site dataset (any site but the MATRIX one)."""
        return self.site != MATRIX_SITE

    def __post_init__(self):
        if self.site_dataset and (self.width, self.height) != (REFERENCE_WIDTH, REFERENCE_HEIGHT):
            raise ValueError(
                'width/height do not apply with a site: each drone\'s image size comes from the site '
                '(image_scale or --fast renders smaller)'
            )
        if not 0.05 <= self.image_scale <= 1.0 or self.ring_radius < 0 or self.altitude < 0:
            raise ValueError(
                f'image_scale must be in [0.05, 1], ring_radius and altitude >= 0; got {self.image_scale}, '
                f'{self.ring_radius}, {self.altitude}'
            )
        if (self.image_scale != 1.0 or self.ring_radius or self.altitude) and not self.site_dataset:
            raise ValueError('image_scale, ring_radius and altitude apply only with a --site other than matrix')
        if self.fast and self.site_dataset:
            self.image_scale = min(self.image_scale, 0.5)  # a site's sizes are its own: --fast halves them
        elif self.fast:
            self.width, self.height = 640, 360
        if self.frames < 1:
            raise ValueError(f'frames must be >= 1, got {self.frames}')
        if self.width < 64 or self.height < 36:
            raise ValueError(f'image size {self.width}x{self.height} is too small')
        if self.image_ext not in ('.png', '.jpg'):
            raise ValueError(f'image_ext must be .png or .jpg, got {self.image_ext!r}')
        if self.frame_period <= 0 or abs(round(self.frame_period / 0.05) * 0.05 - self.frame_period) > 1e-9:
            raise ValueError('frame_period must be a positive multiple of 0.05 s (the drone control tick)')
