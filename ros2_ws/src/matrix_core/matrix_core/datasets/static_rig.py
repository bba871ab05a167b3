"""Readers of static-camera datasets of the same family: Wildtrack and MultiviewX.

Both store one calibration per camera (no per-frame files), ``Image_subsets/C{n}/`` images and
``annotations_positions/`` JSON like MATRIX, but with their own ground grids, units, handedness and file
names. A subclass only states those differences (:class:`RigFormat`); the reading is shared.

Published conventions (checked against each dataset's own files and loaders):

- Wildtrack: ``positionID = col + 480 * row`` on a 480 x 1440 grid of 2.5 cm cells, file world
  ``(x, y) = (-300 + 2.5 col, -900 + 2.5 row)`` centimetres, so a 12 m x 36 m area; calibration
  ``calibrations/intrinsic_zero/intr_<cam>.xml`` (``camera_matrix``, zero distortion, for the undistorted
  images) and ``calibrations/extrinsic/extr_<cam>.xml`` with ``<rvec>``/``<tvec>`` as plain text
  numbers, ``tvec`` in centimetres; right-handed world, z up.
- MultiviewX (synthetic, Unity): ``positionID = col + 1000 * row`` on a 1000 x 640 grid of 2.5 cm cells,
  file world ``(x, y) = (col, row) / 40`` metres, a 25 m (x) x 16 m (y) area; ``calibrations/intrinsic``
  and ``calibrations/extrinsic`` OpenCV matrices, metres. Its world is LEFT-handed (Unity), and its
  ``rvec``/``tvec`` map it into a camera frame that looks down -z: every visible point has a negative
  depth, which ``cv2.projectPoints`` hides (it divides by the depth, so pixels come out right). The
  reader negates y (``world_internal = diag(1, -1, 1) world_file``, as for MATRIX) and turns the camera
  frame to look down +z (``R = -R_file diag(1, -1, 1)``, ``t = -t_file``), which projects every point to
  the same pixels with a positive depth. Internal area: x in [0, 25], y in [-16, 0].
"""

import json
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np

from matrix_core.datasets.base import MultiviewDataset, find_image, numbered_stems
from matrix_core.datasets.opencv_xml import read_matrices
from matrix_core.datasets.types import BoundingBox, DatasetError, PersonAnnotation
from matrix_core.geometry.camera import Camera, pose_matrix


@dataclass(frozen=True)
class RigFormat:
    """What distinguishes one static-rig format from another.

    Attributes:
        camera_files: calibration file stem of each camera, in view order (view i+1 is 'C{i+1}').
        intrinsic_dir: folder of ``intr_<stem>.xml`` under ``calibrations/``.
        metres_per_unit: scale of ``tvec`` and of the grid origin (0.01 for centimetres).
        grid_cols: positionID = col + grid_cols * row.
        grid_cell_m: grid cell size in metres.
        grid_origin_m: (x, y) world metres of cell (0, 0).
        grid_rows: number of grid rows (for the area).
        frame_digits, annotation_digits: zero padding of image and annotation file names.
        left_handed: the files' world is left-handed and their camera frames look down -z (MultiviewX);
            internally y is negated and the camera frames turned (see the module docstring).
    """

    camera_files: tuple
    intrinsic_dir: str
    metres_per_unit: float
    grid_cols: int
    grid_rows: int
    grid_cell_m: float
    grid_origin_m: tuple
    frame_digits: int
    annotation_digits: int
    left_handed: bool = False


# Negates the world y axis: file <-> internal world of a left-handed format (its own inverse).
_MIRROR_Y = np.diag([1.0, -1.0, 1.0])


class StaticRigDataset(MultiviewDataset):
    """Reader for a static multi-camera rig; set ``FORMAT`` in a subclass."""

    FORMAT: RigFormat = None

    def __init__(self, root):
        super().__init__(root)
        fmt = self.FORMAT
        required = ['Image_subsets', f'calibrations/{fmt.intrinsic_dir}', 'calibrations/extrinsic']
        for sub in required:
            if not (self.root / sub).is_dir():
                raise DatasetError(f'{self.root} is not a {self.format_name} folder: missing {sub}/')

    @cached_property
    def views(self) -> tuple:
        present = tuple(
            f'C{i + 1}'
            for i in range(len(self.FORMAT.camera_files))
            if (self.root / 'Image_subsets' / f'C{i + 1}').is_dir()
        )
        if not present:
            raise DatasetError(f'{self.root}/Image_subsets has no C1..CN folders')
        return present

    @cached_property
    def frames(self) -> tuple:
        sets = [set(numbered_stems(self.root / 'Image_subsets' / v)) for v in self.views]
        return tuple(sorted(set.intersection(*sets)))

    @cached_property
    def annotated_frames(self) -> tuple:
        folder = self.root / 'annotations_positions'
        return tuple(numbered_stems(folder, ('.json',))) if folder.is_dir() else ()

    def _file_xy(self, xy) -> np.ndarray:
        """(2,) file-world metres <-> internal world metres (the same map both ways)."""
        xy = np.asarray(xy, dtype=np.float64)
        return xy * [1.0, -1.0] if self.FORMAT.left_handed else xy

    @property
    def area(self) -> tuple:
        f = self.FORMAT
        x0, y0 = f.grid_origin_m
        corners = self._file_xy([[x0, y0], [x0 + f.grid_cols * f.grid_cell_m, y0 + f.grid_rows * f.grid_cell_m]])
        return tuple(float(v) + 0.0 for v in (*corners.min(axis=0), *corners.max(axis=0)))  # + 0.0: no -0.0

    def image_path(self, view, frame):
        return find_image(self.root / 'Image_subsets' / view, f'{frame:0{self.FORMAT.frame_digits}d}')

    def camera(self, view, frame=None):
        return self._cameras[self.view_index(view)]

    @cached_property
    def _cameras(self) -> list:
        return [self._read_camera(self.FORMAT.camera_files[int(view[1:]) - 1]) for view in self.views]

    def _read_camera(self, stem: str) -> Camera:
        """The internal camera of calibration ``stem`` (e.g. 'Camera1'), checked to face the area."""
        f = self.FORMAT
        intr = read_matrices(
            self.root / 'calibrations' / f.intrinsic_dir / f'intr_{stem}.xml',
            ['camera_matrix'],
            optional=['distortion_coefficients'],
        )
        extr = read_matrices(self.root / 'calibrations/extrinsic' / f'extr_{stem}.xml', ['rvec', 'tvec'])
        R, _ = cv2.Rodrigues(extr['rvec'].reshape(3, 1))
        t = extr['tvec'].reshape(3) * f.metres_per_unit
        if f.left_handed:
            R, t = -R @ _MIRROR_Y, -t
        try:
            cam = Camera(
                intr['camera_matrix'],
                pose_matrix(R, t),
                *self.image_size,
                intr.get('distortion_coefficients', np.zeros(5)),
            )
        except ValueError as exc:
            raise DatasetError(f'{self.root}: bad calibration {stem}: {exc}') from exc
        x0, y0, x1, y1 = self.area
        if cam.depth([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])[0] <= 0:
            # A calibration in the other handedness still gives the right pixels through cv2.projectPoints,
            # but every point behind the camera here: say so instead of reading nonsense.
            hand = 'left' if f.left_handed else 'right'
            raise DatasetError(
                f'{self.root}: calibration {stem} puts the centre of the area {self.area} behind '
                f'the camera: not a {self.format_name} calibration ({hand}-handed world)'
            )
        return cam

    def position_to_world(self, position_id: int) -> np.ndarray:
        f = self.FORMAT
        col, row = position_id % f.grid_cols, position_id // f.grid_cols
        return self._file_xy([f.grid_origin_m[0] + col * f.grid_cell_m, f.grid_origin_m[1] + row * f.grid_cell_m])

    def world_to_position(self, xy) -> int:
        f = self.FORMAT
        x, y = self._file_xy(xy)
        col = int(np.floor((x - f.grid_origin_m[0]) / f.grid_cell_m + 1e-9))
        row = int(np.floor((y - f.grid_origin_m[1]) / f.grid_cell_m + 1e-9))
        if not (0 <= col < f.grid_cols and 0 <= row < f.grid_rows):
            raise ValueError(f'position {xy} is outside the {self.format_name} grid')
        return col + f.grid_cols * row

    def annotations(self, frame):
        path = self.root / 'annotations_positions' / f'{frame:0{self.FORMAT.annotation_digits}d}.json'
        if not path.is_file():
            return []
        try:
            persons = []
            for e in json.loads(path.read_text()):
                boxes = {}
                for v in e['views']:
                    vals = [v['xmin'], v['ymin'], v['xmax'], v['ymax']]
                    if vals != [-1, -1, -1, -1] and v['viewNum'] < len(self.FORMAT.camera_files):
                        boxes[f"C{v['viewNum'] + 1}"] = BoundingBox(*map(float, vals))
                pid = int(e['positionID'])
                persons.append(PersonAnnotation(int(e['personID']), pid, self.position_to_world(pid), boxes))
        except (ValueError, KeyError, TypeError) as exc:
            raise DatasetError(f'malformed annotation file {path}: {exc!r}') from exc
        return persons


class WildtrackDataset(StaticRigDataset):
    """Wildtrack: 7 cameras, centimetre calibration, 480 (x) x 1440 (y) grid of 2.5 cm from (-3, -9) m."""

    format_name = 'wildtrack'
    FORMAT = RigFormat(
        camera_files=('CVLab1', 'CVLab2', 'CVLab3', 'CVLab4', 'IDIAP1', 'IDIAP2', 'IDIAP3'),
        intrinsic_dir='intrinsic_zero',
        metres_per_unit=0.01,
        grid_cols=480,
        grid_rows=1440,
        grid_cell_m=0.025,
        grid_origin_m=(-3.0, -9.0),
        frame_digits=8,
        annotation_digits=8,
    )


class MultiviewXDataset(StaticRigDataset):
    """MultiviewX: 6 cameras, metre calibration, left-handed world, 1000 (x) x 640 (y) grid of 2.5 cm from
    (0, 0) m: a 25 m x 16 m area."""

    format_name = 'multiviewx'
    FORMAT = RigFormat(
        camera_files=tuple(f'Camera{i}' for i in range(1, 7)),
        intrinsic_dir='intrinsic',
        metres_per_unit=1.0,
        grid_cols=1000,
        grid_rows=640,
        grid_cell_m=0.025,
        grid_origin_m=(0.0, 0.0),
        frame_digits=4,
        annotation_digits=5,
        left_handed=True,
    )
