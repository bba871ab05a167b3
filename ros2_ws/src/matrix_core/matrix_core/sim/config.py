"""Scene configuration of the simulator: plain dataclasses loaded from a YAML file.

A config file describes ONE scene variant (area, floor, block, checkerboards, crowd, drones, buildings). The
three shipped variants live in ``matrix_core/sim/configs/{simple,complex,modified}.yaml``; users can pass
the path of their own file. Unknown keys are rejected so that typos do not silently fall back to defaults.

Convention: internal world frame (right-handed, metres, z up, ground z = 0). The real MATRIX square is
``MATRIX_AREA`` (x in [0, 30], y in [-30, 0]). A scene may have any area; only a sequence written in the MATRIX
folder format must stay inside that square (:func:`check_matrix_grid`), because MATRIX positionIDs are a
300 x 300 grid of 0.1 m cells. A site (``simulate --site``) is written as a site dataset, with metric
positions, and has no such limit.
"""

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path


from matrix_core.datasets.matrix_conventions import MATRIX_AREA
from matrix_core.settings import read_yaml

CONFIG_DIR = Path(__file__).resolve().parent / 'configs'
VARIANTS = ('simple', 'complex', 'modified')


@dataclass
class BoxConfig:
    """Axis-aligned box standing on the ground (the central block, pillars)."""

    center: list = field(default_factory=lambda: [15.0, -15.0])
    size: list = field(default_factory=lambda: [5.0, 5.0])
    height: float = 10.0
    color: list = field(default_factory=lambda: [20, 20, 110])  # BGR of the lit side
    stripes: bool = False  # horizontal stripes of a darker shade (the "modified" block)

    def __post_init__(self):
        if len(self.center) != 2 or len(self.size) != 2 or min(self.size) <= 0 or self.height <= 0:
            raise ValueError(f'box needs center [x, y], positive size [sx, sy] and height, got {self}')
        if len(self.color) != 3:
            raise ValueError(f'box color must be [b, g, r], got {self.color}')

    @property
    def bounds(self) -> tuple:
        """(x_min, y_min, x_max, y_max) metres."""
        (cx, cy), (sx, sy) = self.center, self.size
        return (cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2)


@dataclass
class BoardConfig:
    """A checkerboard lying on the ground: ``squares`` x ``squares`` squares of ``square_m``.

    ``origin`` is its (x_min, y_min) corner; square (i, j) is black when i + j is even. The inner corners
    are at ``origin + square_m * (i, j)``, i, j = 1..squares-1, on the plane z = ``z`` (0.1 m in MATRIX).
    """

    origin: list = field(default_factory=lambda: [5.5, -26.0])
    squares: int = 20
    square_m: float = 0.25
    z: float = 0.1

    def __post_init__(self):
        if len(self.origin) != 2 or self.squares < 3 or self.square_m <= 0:
            raise ValueError(f'invalid checkerboard {self}')

    @property
    def bounds(self) -> tuple:
        side = self.squares * self.square_m
        return (self.origin[0], self.origin[1], self.origin[0] + side, self.origin[1] + side)

    @property
    def squares_xy(self) -> tuple:
        """(squares along x, squares along y)."""
        return (self.squares, self.squares)

    @property
    def dark_parity(self) -> int:
        """Square (i, j) counted from ``origin`` is black when ``(i + j + dark_parity)`` is even."""
        return 0


@dataclass
class CrowdConfig:
    """Pedestrians: count, body sizes and walking behaviour (social-force model, see ``crowd.py``)."""

    count: int = 40
    speed: float = 1.2  # preferred walking speed, m/s
    speed_std: float = 0.1
    height_range: list = field(default_factory=lambda: [1.5, 1.95])  # body height, metres
    body_radius: float = 0.22  # unused by the articulated body (sim/person_model.py); kept for old files
    leg_radius: float = 0.16  # collision / annotation radius (= the 0.16 m annotation cylinder)
    dress_fraction: float = 0.2  # share of people in a dress (a short cone from the waist)
    walking_pose: bool = True  # legs and arms swing while walking; false: everybody in the rest pose
    keep_out_margin: float = 0.5  # metres kept free around the block and inside the area border

    def __post_init__(self):
        if self.count < 0 or self.speed <= 0 or len(self.height_range) != 2 or not 0.0 <= self.dress_fraction <= 1.0:
            raise ValueError(f'invalid crowd config {self}')


@dataclass
class DroneConfig:
    """Drone ring, motion and gimbal PID (the paper's gains; error measured in 1920-px-wide pixels)."""

    count: int = 8
    ring_half_side: float = 20.5  # home positions on a square ring this far from the scene centre (metres)
    altitude: float = 12.3
    reference_ring_half_side: float = 22.7  # static reference poses (reference/ folder), like the real sample
    reference_altitude: float = 12.29
    target_xy: float = 3.0  # random targets within +- this of home in x and y
    target_z_band: float = 1.0  # ... and within this band in z around the altitude
    v_max: float = 1.5
    retarget_period: list = field(default_factory=lambda: [1.0, 2.5])  # seconds between new targets
    position_gain: float = 0.4  # velocity command = gain * (target - position), 1/s
    max_accel: float = 1.5  # m/s^2, also sets the body tilt (atan(a / g)) that the gimbal must correct
    tilt_lag_s: float = 0.4  # the body attitude (and so the acceleration) follows the command with this lag
    kp: float = 0.0002
    ki: float = 0.00002
    kd: float = 0.0001
    aim_jitter: float = 3.0  # the aimed point wanders within +- this of the centre (metres)
    hfov_deg: float = 70.0

    def __post_init__(self):
        # 8 places on the MATRIX ring (D1..D8); a site places up to 16 drones itself (sim/site_rig.py)
        if not 1 <= self.count <= 16:
            raise ValueError(f'drone count must be 1..16, got {self.count}')
        if not 10.0 <= self.hfov_deg <= 150.0 or self.v_max <= 0 or self.altitude <= 0:
            raise ValueError(f'invalid drone config {self}')


@dataclass
class LightingConfig:
    """Per-sequence lighting randomisation (``sim/lighting.py``): each value is drawn uniformly from its
    [low, high] range; ``dusk`` 0 is clear day, 1 evening (low weak sun, soft shadows, dark sky)."""

    enabled: bool = True  # false: the fixed light of the plain scene
    azimuth_deg: list = field(default_factory=lambda: [0.0, 360.0])
    elevation_deg: list = field(default_factory=lambda: [25.0, 70.0])
    sun_intensity: list = field(default_factory=lambda: [0.3, 0.55])
    ambient: list = field(default_factory=lambda: [0.45, 0.65])
    shadow_factor: list = field(default_factory=lambda: [0.35, 0.85])  # shadowed / lit ground brightness
    dusk: list = field(default_factory=lambda: [0.0, 1.0])
    dusk_facade_dimming: float = 0.55  # facades are this much darker at full dusk
    level: list = field(default_factory=lambda: [0.85, 1.08])  # overall light level
    tint_std: float = 0.025  # per-channel light colour spread

    def __post_init__(self):
        for name in ('azimuth_deg', 'elevation_deg', 'sun_intensity', 'ambient', 'shadow_factor', 'dusk', 'level'):
            lo_hi = getattr(self, name)
            if len(lo_hi) != 2 or lo_hi[0] > lo_hi[1]:
                raise ValueError(f'lighting.{name} must be [low, high], got {lo_hi}')
        if not (
            0 < self.elevation_deg[0]
            and self.elevation_deg[1] <= 90
            and 0 <= self.dusk[0]
            and self.dusk[1] <= 1
            and 0 < self.shadow_factor[0]
            and self.shadow_factor[1] <= 1
        ):
            raise ValueError(f'invalid lighting config {self}')


@dataclass
class CameraEffectsConfig:
    """Per-drone camera effects (``sim/camera_effects.py``): drawn per drone and sequence from the
    [low, high] ranges, with a small per-frame jitter. Blur sigma is in pixels of a 640-px-wide image."""

    enabled: bool = True  # false: the plain pinhole render
    supersample: float = 1.5  # render at this factor of the output size and downsample (INTER_AREA)
    exposure: list = field(default_factory=lambda: [0.85, 1.15])  # gain
    white_balance: list = field(default_factory=lambda: [0.94, 1.06])  # blue gain; red 2 - blue, green 1
    gamma: list = field(default_factory=lambda: [0.85, 1.15])
    contrast: list = field(default_factory=lambda: [0.9, 1.1])
    blur_sigma: list = field(default_factory=lambda: [0.0, 0.6])
    noise_sigma: list = field(default_factory=lambda: [0.5, 2.5])  # read noise, grey levels at 1920 px
    shot_noise: list = field(default_factory=lambda: [0.0, 0.015])  # variance per grey level at 1920 px
    vignetting: list = field(default_factory=lambda: [0.0, 0.25])  # brightness loss in the corners
    jpeg_quality: list = field(default_factory=lambda: [70, 95])  # at 1920 px
    jitter: float = 0.02  # relative per-frame jitter of exposure and white balance

    def __post_init__(self):
        for name in (
            'exposure',
            'white_balance',
            'gamma',
            'contrast',
            'blur_sigma',
            'noise_sigma',
            'shot_noise',
            'vignetting',
            'jpeg_quality',
        ):
            lo_hi = getattr(self, name)
            if len(lo_hi) != 2 or lo_hi[0] > lo_hi[1] or lo_hi[0] < 0:
                raise ValueError(f'camera_effects.{name} must be [low, high] >= 0, got {lo_hi}')
        if not 1.0 <= self.supersample <= 4.0 or not 1 <= self.jpeg_quality[0] <= self.jpeg_quality[1] <= 100:
            raise ValueError(f'invalid camera_effects config {self}')


@dataclass
class DistractorConfig:
    """Per-sequence randomisation of the static scene (seeded from the sequence's child generator 4):
    distractor objects (see ``distractors.py``) and the variety of ground materials and facades.
    ``enabled: false`` renders the plain scene."""

    enabled: bool = True
    corner_posts: bool = True  # a post with a coloured sphere just outside each area corner
    inside: int = 4  # thin objects (poles, bollards, posts with spheres, bins) in the walkable area
    near: int = 8  # thin or low objects between the area and the drone ring
    far: int = 16  # anything (trees, lamp posts, cars, benches...) beyond the drone ring
    ground_variety: bool = True  # random floor material, colour, dirt patches and surround paving
    facade_variety: bool = True  # dusk (lit windows) / daytime facades, shop fronts

    def __post_init__(self):
        if min(self.inside, self.near, self.far) < 0:
            raise ValueError(f'distractor counts must be >= 0, got {self}')


@dataclass
class SceneConfig:
    """One scene variant. ``area`` is the walkable square (x_min, y_min, x_max, y_max), internal metres."""

    name: str = 'complex'
    area: list = field(default_factory=lambda: list(MATRIX_AREA))
    floor: str = 'cement'  # cement | cobblestone
    floor_color: list = field(default_factory=lambda: [178, 182, 186])  # BGR mean of the walkable floor
    markings: bool = True  # painted joint lines and the area outline
    block: BoxConfig = None  # the central occluder; None for no obstruction
    pillars: list = field(default_factory=list)  # more BoxConfig obstacles (drawn and occluding)
    boards: list = field(default_factory=list)  # BoardConfig list
    crowd: CrowdConfig = field(default_factory=CrowdConfig)
    drones: DroneConfig = field(default_factory=DroneConfig)
    building_distance: float = 34.0  # facades stand on a square ring this far from the centre
    building_height: list = field(default_factory=lambda: [14.0, 30.0])
    lighting: LightingConfig = field(default_factory=LightingConfig)
    camera_effects: CameraEffectsConfig = field(default_factory=CameraEffectsConfig)
    distractors: DistractorConfig = field(default_factory=DistractorConfig)

    def __post_init__(self):
        if self.floor not in ('cement', 'cobblestone'):
            raise ValueError(f'floor must be cement or cobblestone, got {self.floor!r}')
        if len(self.area) != 4 or not (self.area[0] < self.area[2] and self.area[1] < self.area[3]):
            raise ValueError(
                f'area must be [x_min, y_min, x_max, y_max] with x_min < x_max, y_min < y_max, got {self.area}'
            )
        if self.building_distance <= self.drones.ring_half_side + 2.0:
            raise ValueError('building_distance must be beyond the drone ring (+2 m)')

    @property
    def center(self) -> tuple:
        x0, y0, x1, y1 = self.area
        return ((x0 + x1) / 2.0, (y0 + y1) / 2.0)

    @property
    def obstacles(self) -> list:
        """Every occluding box on the ground (block first)."""
        return ([self.block] if self.block is not None else []) + list(self.pillars)


def check_matrix_grid(area) -> None:
    """ValueError unless ``area`` lies inside the MATRIX positionID grid (``MATRIX_AREA``): what a sequence in
    the MATRIX folder format needs (a site dataset, ``simulate --site``, does not)."""
    x0, y0, x1, y1 = area
    gx0, gy0, gx1, gy1 = MATRIX_AREA  # the positionID grid
    if not (gx0 <= x0 < x1 <= gx1 and gy0 <= y0 < y1 <= gy1):
        raise ValueError(
            f'area {list(area)} must lie inside the MATRIX position grid {list(MATRIX_AREA)} to be written in the '
            f'MATRIX format; simulate --site SITE writes any area as a site dataset'
        )


def _build(cls, data, where: str):
    if data is None:
        return None
    if not isinstance(data, dict):
        raise ValueError(f'{where}: expected a mapping, got {data!r}')
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = set(data) - names
    if unknown:
        raise ValueError(f'{where}: unknown keys {sorted(unknown)} (known: {sorted(names)})')
    return cls(**data)


def scene_config_from_dict(data: dict) -> SceneConfig:
    """Nested dict (as in the YAML files) -> validated :class:`SceneConfig`."""
    data = dict(data)
    data['block'] = _build(BoxConfig, data.get('block'), 'block')
    data['pillars'] = [_build(BoxConfig, p, f'pillars[{i}]') for i, p in enumerate(data.get('pillars') or [])]
    data['boards'] = [_build(BoardConfig, b, f'boards[{i}]') for i, b in enumerate(data.get('boards') or [])]
    data['crowd'] = _build(CrowdConfig, data.get('crowd', {}), 'crowd')
    data['drones'] = _build(DroneConfig, data.get('drones', {}), 'drones')
    data['lighting'] = _build(LightingConfig, data.get('lighting', {}), 'lighting')
    data['camera_effects'] = _build(CameraEffectsConfig, data.get('camera_effects', {}), 'camera_effects')
    data['distractors'] = _build(DistractorConfig, data.get('distractors', {}), 'distractors')
    return _build(SceneConfig, data, 'scene')


def load_scene_config(name_or_path) -> SceneConfig:
    """Load a shipped variant by name ('simple', 'complex', 'modified') or a YAML file by path."""
    path = Path(name_or_path)
    if str(name_or_path) in VARIANTS:
        path = CONFIG_DIR / f'{name_or_path}.yaml'
    if not path.is_file():
        raise FileNotFoundError(f'scene config {name_or_path!r} is neither a variant {VARIANTS} nor a file')
    try:
        return scene_config_from_dict(read_yaml(path))
    except (TypeError, ValueError) as exc:
        raise ValueError(f'{path}: {exc}') from exc


def scene_config_to_dict(config: SceneConfig) -> dict:
    """Plain dict of a config (stored in ``matrix_tracker_meta.json`` so a sequence documents its scene)."""
    return dataclasses.asdict(config)
