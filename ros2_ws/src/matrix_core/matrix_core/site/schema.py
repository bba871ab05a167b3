"""What a site file describes, as plain frozen dataclasses (built and validated by :mod:`matrix_core.site.load`).

Frames and units: the INTERNAL world frame of :mod:`matrix_core.geometry.camera` (right-handed, metres,
z up, ground z = 0); pixels in the pixel-centre convention; an area or footprint is
``(x_min, y_min, x_max, y_max)`` metres, the convention of ``MATRIX_AREA``.
"""

import enum
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from matrix_core.calib.board import Checkerboard


class ReferenceSource(enum.Enum):
    """Where a site's reference images and calibrations come from."""

    FILES = 'files'  # every drone names its reference image and calibration (paths under references.root)
    SIMULATE = 'simulate'  # none yet: the simulator is to render them; commands that need them refuse the site


class CalibrationFormat(enum.Enum):
    """File format of a reference calibration."""

    # MATRIX's pair of OpenCV XML files (intr_*.xml: camera_matrix, distortion_coefficients; extr_*.xml:
    # rvec, tvec) in the MATRIX file conventions (left-handed world, mirrored image), converted by
    # matrix_core.datasets.matrix_conventions.camera_from_file.
    MATRIX_XML = 'matrix_xml'
    # Two YAML files in the internal conventions (matrix_core.geometry.camera), as `site init` writes them:
    # intrinsic {image_size: [w, h], K: 9 numbers, dist: 5 numbers}, extrinsic {cam_T_world: 4 x 4 rows}.
    CAMERA_YAML = 'camera_yaml'


@dataclass(frozen=True)
class CameraSpec:
    """A drone camera's intrinsics.

    Attributes:
        image_size: (width, height) pixels.
        K: (3, 3) intrinsic matrix, pixel-centre convention.
        dist: (5,) OpenCV distortion coefficients (k1, k2, p1, p2, k3); zeros for an ideal pinhole.
    """

    image_size: tuple
    K: np.ndarray
    dist: np.ndarray

    @property
    def hfov_deg(self) -> float:
        """Horizontal field of view in degrees (of the pinhole, ignoring distortion)."""
        return float(np.degrees(2.0 * np.arctan2(self.image_size[0] / 2.0, self.K[0, 0])))


@dataclass(frozen=True)
class CalibrationRef:
    """Where a reference calibration is stored: paths as the site file writes them, relative to the site's
    ``references.root`` (:func:`matrix_core.site.references.resolve` makes them absolute)."""

    format: CalibrationFormat
    intrinsic: Path
    extrinsic: Path

    @property
    def files(self) -> tuple:
        """Every file the calibration is made of."""
        return (self.intrinsic, self.extrinsic)


@dataclass(frozen=True)
class ReferenceSpec:
    """A drone's reference: one image of the (empty) scene at a known pose and that pose's calibration.

    ``image``: a path relative to the site's ``references.root``, as written in the file. ``stamp_s``: the
    header stamp (seconds) of the recorded frame the reference was taken from (``site init`` from a bag), None
    otherwise; with a recording's ground truth it names the reference frame's true camera, against which the
    graph monitor scores the registration."""

    image: Path
    calibration: CalibrationRef
    stamp_s: float = None


@dataclass(frozen=True)
class DroneSpec:
    """One drone.

    Attributes:
        name: the drone's name, also its topic namespace (``<name>/image_raw``).
        camera: its intrinsics and image size.
        reference: its reference image and calibration; None when the site's references are to be simulated.
        altitude_m: nominal flying height above the ground (metres), None when not given.
        home_xy: (2,) nominal ground position (metres) it hovers over, None when not given.
    """

    name: str
    camera: CameraSpec
    reference: ReferenceSpec = None
    altitude_m: float = None
    home_xy: tuple = None


@dataclass(frozen=True)
class ObstacleSpec:
    """A static box standing on the ground: it hides the ground behind it and blocks lines of sight.

    ``footprint`` (x_min, y_min, x_max, y_max) metres; ``height`` metres above the ground."""

    name: str
    footprint: tuple
    height: float

    @property
    def box(self) -> tuple:
        """(x0, y0, x1, y1, height): the group of five numbers the ground masks and occlusion tests take."""
        return (*self.footprint, self.height)


@dataclass(frozen=True)
class Site:
    """Everything site-specific: the ground area, the BEV cell, the drones, the boards, the obstacles.

    Attributes:
        path: the site file (absolute).
        name: a short name of the site.
        area: (x_min, y_min, x_max, y_max) metres, the ground where people are detected and tracked.
        cell_m: BEV grid cell size (metres).
        drones: tuple of :class:`DroneSpec` (1 to 16, distinct names), in the order the fuser sees them.
        boards: tuple of :class:`~matrix_core.calib.board.Checkerboard` lying inside ``area``.
        obstacles: tuple of :class:`ObstacleSpec`.
        references: how the references are given (:class:`ReferenceSource`).
        references_root: the folder the drones' reference paths are relative to (absolute), None when it
            names an environment variable that is not set (an error only for a command that needs the files).
        references_root_text: ``references.root`` as written in the file (for messages).
    """

    path: Path
    name: str
    area: tuple
    cell_m: float
    drones: tuple
    boards: tuple
    obstacles: tuple
    references: ReferenceSource
    references_root: Path
    references_root_text: str

    @property
    def drone_names(self) -> tuple:
        return tuple(d.name for d in self.drones)

    def drone(self, name: str) -> DroneSpec:
        """The drone called ``name``; KeyError naming the site's drones otherwise."""
        for d in self.drones:
            if d.name == name:
                return d
        raise KeyError(f'{self.path}: no drone {name!r} (drones: {", ".join(self.drone_names)})')

    @property
    def obstacle_boxes(self) -> list:
        """Flat list of groups ``x0 y0 x1 y1 height``, one per obstacle (the settings' ``exclude_boxes`` form)."""
        return [float(v) for o in self.obstacles for v in o.box]

    def board(self, name: str) -> Checkerboard:
        for b in self.boards:
            if b.name == name:
                return b
        raise KeyError(f'{self.path}: no board {name!r}')

    def grid_shape(self, margin_m: float = 0.0) -> tuple:
        """(rows, cols) of the BEV grid over ``area`` grown by ``margin_m`` with cells of ``cell_m``."""
        from matrix_core.geometry.grid import BevGrid

        x0, y0, x1, y1 = self.area
        m = margin_m
        return BevGrid(x0 - m, y0 - m, x1 + m, y1 + m, self.cell_m).shape
