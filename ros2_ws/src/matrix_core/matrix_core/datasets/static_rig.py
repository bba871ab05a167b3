"""Readers of static-camera datasets of the same family: Wildtrack and MultiviewX.

Both store one calibration per camera (no per-frame files), ``Image_subsets/C{n}/`` images and
``annotations_positions/`` JSON like MATRIX, but with their own ground grids, units and file names.
A subclass only states those differences (:class:`RigFormat`); the reading is shared.
"""

import json
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from matrix_core.datasets.base import MultiviewDataset, find_image, numbered_stems
from matrix_core.datasets.opencv_xml import read_matrices
from matrix_core.datasets.types import BoundingBox, DatasetError, PersonAnnotation
from matrix_core.geometry.camera import Camera


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
        present = tuple(f'C{i + 1}' for i in range(len(self.FORMAT.camera_files))
                        if (self.root / 'Image_subsets' / f'C{i + 1}').is_dir())
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

    @property
    def area(self) -> tuple:
        f = self.FORMAT
        x0, y0 = f.grid_origin_m
        return (x0, y0, x0 + f.grid_cols * f.grid_cell_m, y0 + f.grid_rows * f.grid_cell_m)

    def image_path(self, view, frame):
        return find_image(self.root / 'Image_subsets' / view, f'{frame:0{self.FORMAT.frame_digits}d}')

    def camera(self, view, frame=None):
        return self._cameras[self.view_index(view)]

    @cached_property
    def _cameras(self) -> list:
        f = self.FORMAT
        cams = []
        for view in self.views:
            stem = f.camera_files[int(view[1:]) - 1]
            intr = read_matrices(self.root / 'calibrations' / f.intrinsic_dir / f'intr_{stem}.xml',
                                 ['camera_matrix', 'distortion_coefficients'])
            extr = read_matrices(self.root / 'calibrations/extrinsic' / f'extr_{stem}.xml', ['rvec', 'tvec'])
            try:
                cams.append(Camera.from_rvec_tvec(intr['camera_matrix'], extr['rvec'],
                                                  extr['tvec'].reshape(3) * f.metres_per_unit,
                                                  *self.image_size, intr['distortion_coefficients']))
            except ValueError as exc:
                raise DatasetError(f'{self.root}: bad calibration {stem}: {exc}') from exc
        return cams

    def position_to_world(self, position_id: int) -> np.ndarray:
        f = self.FORMAT
        col, row = position_id % f.grid_cols, position_id // f.grid_cols
        return np.array([f.grid_origin_m[0] + col * f.grid_cell_m, f.grid_origin_m[1] + row * f.grid_cell_m])

    def world_to_position(self, xy) -> int:
        f = self.FORMAT
        col = int(np.floor((xy[0] - f.grid_origin_m[0]) / f.grid_cell_m + 1e-9))
        row = int(np.floor((xy[1] - f.grid_origin_m[1]) / f.grid_cell_m + 1e-9))
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
    """Wildtrack: 7 cameras, centimetre calibration, 480 x 1440 grid of 2.5 cm from (-3, -9) m."""

    format_name = 'wildtrack'
    FORMAT = RigFormat(
        camera_files=('CVLab1', 'CVLab2', 'CVLab3', 'CVLab4', 'IDIAP1', 'IDIAP2', 'IDIAP3'),
        intrinsic_dir='intrinsic_zero', metres_per_unit=0.01, grid_cols=480, grid_rows=1440,
        grid_cell_m=0.025, grid_origin_m=(-3.0, -9.0), frame_digits=8, annotation_digits=8)


class MultiviewXDataset(StaticRigDataset):
    """MultiviewX: 6 cameras, metre calibration, 640 x 1000 grid of 2.5 cm from (0, 0) m."""

    format_name = 'multiviewx'
    FORMAT = RigFormat(
        camera_files=tuple(f'Camera{i}' for i in range(1, 7)), intrinsic_dir='intrinsic',
        metres_per_unit=1.0, grid_cols=640, grid_rows=1000, grid_cell_m=0.025, grid_origin_m=(0.0, 0.0),
        frame_digits=4, annotation_digits=5)
