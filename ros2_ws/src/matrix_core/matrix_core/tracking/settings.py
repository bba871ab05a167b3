"""Settings of the BEV tracker (CLI flags of ``matrix-tracker track`` and ROS parameters of ``fuse``)."""

from dataclasses import dataclass, field

from matrix_core.settings import Settings


@dataclass
class TrackerSettings(Settings):
    """ByteTrack-style association of ground-plane detections. Distances in metres, times in seconds.

    ``birth_hits``, ``high_score``/``low_score``, ``accel_noise`` and ``measurement_noise_m`` were chosen on
    the detector's validation sequences (simulated seeds 111-114 and the real sample frames 0-4, the default
    checkpoint): ``python scripts/tune_tracker.py``. ``gate_m`` and ``max_gate_m`` were chosen on
    the tuning part of ``python scripts/bench_tracker.py --tune`` (long noisy runs of trajectories), which
    would also pick ``birth_hits`` 2 and then ``report_coasting`` 2: right for a detector with frequent
    confident false positives, but on the real frames the default checkpoint has none and the later birth
    only costs (docs/detector.md)."""

    gate_m: float = field(
        default=1.25, metadata={'help': 'largest distance (m) between a track and a detection that may be paired'}
    )
    gate_growth_m: float = field(
        default=1.0,
        metadata={
            'help': 'the gate of a track coasting through a gap grows by this much (m) per missed frame '
            '(people turn while unseen)'
        },
    )
    max_gate_m: float = field(
        default=4.0,
        metadata={'help': 'the grown gate of a coasting track is at most this (m); at least gate_m'},
    )
    high_score: float = field(
        default=0.5, metadata={'help': 'detections at or above this score are matched first and may start tracks'}
    )
    low_score: float = field(
        default=0.2,
        metadata={
            'help': 'detections below this score are ignored; between low and high they only extend confirmed '
            'tracks (ByteTrack second stage)'
        },
    )
    birth_hits: int = field(
        default=1, metadata={'help': 'consecutive matched frames before a track gets an id and is reported'}
    )
    max_misses: int = field(
        default=3, metadata={'help': 'a confirmed track is deleted after this many frames in a row without a detection'}
    )
    frame_interval_s: float = field(default=0.5, metadata={'help': 'time between frames (s); MATRIX is 2 fps'})
    accel_noise: float = field(default=2.0, metadata={'help': 'Kalman process noise: std of the acceleration (m/s^2)'})
    measurement_noise_m: float = field(
        default=0.3, metadata={'help': 'Kalman measurement noise: std of a detection position (m)'}
    )
    confirm_first_frame: bool = field(
        default=True,
        metadata={
            'help': 'tracks started in the first frame (after construction or reset()) get an id at once, as in '
            'ByteTrack: everyone present at the start would otherwise be missed for birth_hits - 1 frames'
        },
    )
    report_coasting: int = field(
        default=1,
        metadata={
            'help': 'also report confirmed tracks that missed up to this many frames in a row, at their Kalman '
            'prediction (0: only matched tracks)'
        },
    )
    use_offsets: bool = field(
        default=True, metadata={'help': 'associate with the detections\' tracking offsets (CenterTrack) when present'}
    )

    def check(self) -> None:
        for name in ('gate_m', 'frame_interval_s', 'accel_noise', 'measurement_noise_m'):
            if not getattr(self, name) > 0:
                raise ValueError(f'{name} must be positive, got {getattr(self, name)}')
        if self.gate_growth_m < 0:
            raise ValueError(f'gate_growth_m must be >= 0, got {self.gate_growth_m}')
        if not self.max_gate_m > 0:
            raise ValueError(f'max_gate_m must be positive, got {self.max_gate_m}')
        if not 0 <= self.low_score <= self.high_score:
            raise ValueError(f'need 0 <= low_score <= high_score, got {self.low_score}, {self.high_score}')
        if self.report_coasting < 0:
            raise ValueError(f'report_coasting must be >= 0, got {self.report_coasting}')
        if self.birth_hits < 1 or self.max_misses < 0:
            raise ValueError(f'birth_hits must be >= 1 and max_misses >= 0, got {self.birth_hits}, {self.max_misses}')
