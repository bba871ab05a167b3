"""Settings of the simulator: the flags of ``matrix-tracker simulate`` (same names if it becomes a node)."""

from dataclasses import dataclass, field

from matrix_core.bags.clock import DEFAULT_CLOCK
from matrix_core.reference_size import REFERENCE_HEIGHT, REFERENCE_WIDTH


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
    out: str = field(default='out/sim', metadata={'help': 'output MATRIX folder (must be empty or absent)'})
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

    def __post_init__(self):
        if self.fast:
            self.width, self.height = 640, 360
        if self.frames < 1:
            raise ValueError(f'frames must be >= 1, got {self.frames}')
        if self.width < 64 or self.height < 36:
            raise ValueError(f'image size {self.width}x{self.height} is too small')
        if self.image_ext not in ('.png', '.jpg'):
            raise ValueError(f'image_ext must be .png or .jpg, got {self.image_ext!r}')
        if self.frame_period <= 0 or abs(round(self.frame_period / 0.05) * 0.05 - self.frame_period) > 1e-9:
            raise ValueError('frame_period must be a positive multiple of 0.05 s (the drone control tick)')
