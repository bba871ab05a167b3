"""Reader of the MATRIX folder format (real MATRIX data and our simulator's output).

All file-convention conversions go through :mod:`matrix_core.datasets.matrix_conventions`.
"""

import json
import re
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from matrix_core.datasets import matrix_conventions as conv
from matrix_core.datasets.base import (
    IMAGE_EXTENSIONS,
    MultiviewDataset,
    find_image,
    image_size,
    numbered_stems,
    read_image,
)
from matrix_core.datasets.opencv_xml import read_matrices
from matrix_core.datasets.types import BoundingBox, DatasetError, PersonAnnotation, PlaneCorrespondences
from matrix_core.geometry.camera import Camera

META_FILE = 'matrix_tracker_meta.json'
_INTR_RE = re.compile(r'intr_Drone(\d+)_(\d+)\.xml$')


def _read_table(path: Path, columns: int) -> np.ndarray:
    """Whitespace table with ``columns`` numeric columns -> (N, columns) float array (blank lines skipped)."""
    try:
        rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
        arr = np.array(rows, dtype=np.float64).reshape(-1, columns)
    except (OSError, ValueError) as exc:
        raise DatasetError(f'malformed table {path}: {exc}') from exc
    return arr


class MatrixDataset(MultiviewDataset):
    """A MATRIX-format folder: ``image_subsets/D{n}/TTTT.{png,jpg}``, per-frame ``calibrations/``,
    ``annotations_positions/``, ``matchings/{Planes,Pedestrians}``, optional ``reference/``.

    ``views`` are 'D1'..'D8'; ``frames`` those that have images and a calibration for every view.
    """

    format_name = 'matrix'

    def __init__(self, root):
        super().__init__(root)
        for sub in ('image_subsets', 'calibrations/intrinsic', 'calibrations/extrinsic'):
            if not (self.root / sub).is_dir():
                raise DatasetError(f'{self.root} is not a MATRIX folder: missing {sub}/')
        meta_path = self.root / META_FILE
        try:
            self.meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
        except ValueError as exc:
            raise DatasetError(f'malformed {meta_path}: {exc}') from None
        if not isinstance(self.meta, dict):
            raise DatasetError(f'malformed {meta_path}: expected a JSON object')

    # ----- structure -------------------------------------------------------------------------------
    @cached_property
    def _calibrated(self) -> dict:
        """drone number -> set of frames with an intrinsic file."""
        out = {}
        for p in (self.root / 'calibrations/intrinsic').iterdir():
            m = _INTR_RE.match(p.name)
            if m:
                out.setdefault(int(m.group(1)), set()).add(int(m.group(2)))
        return out

    @cached_property
    def views(self) -> tuple:
        drones = sorted(
            int(p.name[1:])
            for p in (self.root / 'image_subsets').iterdir()
            if p.is_dir() and p.name.startswith('D') and p.name[1:].isdigit()
        )
        if not drones:
            raise DatasetError(f'{self.root}/image_subsets has no D1..DN folders')
        return tuple(conv.view_name(d) for d in drones)

    def _image_frames(self, view: str) -> set:
        """Frames of the images of ``view``; :class:`DatasetError` naming a file numbered otherwise than
        ``TTTT`` (4 digits, zero-padded: the name every reader of the format looks up)."""
        folder = self.root / 'image_subsets' / view
        frames = numbered_stems(folder)
        misnamed = sorted(
            p.name
            for p in folder.iterdir()
            if p.stem.isdigit() and p.stem != f'{int(p.stem):04d}' and p.suffix.lower() in IMAGE_EXTENSIONS
        )
        if misnamed:
            raise DatasetError(
                f'{folder}: image files must be named by their frame as TTTT (e.g. 0012.png); '
                f'misnamed: {", ".join(misnamed[:5])}'
            )
        return set(frames)

    @cached_property
    def frames(self) -> tuple:
        common = None
        for view in self.views:
            d = conv.drone_number(view)
            have = self._image_frames(view) & self._calibrated.get(d, set())
            common = have if common is None else common & have
        return tuple(sorted(common or ()))

    @cached_property
    def incomplete_frames(self) -> dict:
        """frame -> why it is not in :attr:`frames`: frames some view has an image or calibration of, but not
        every view both (named per view), so that a command can report them instead of dropping them silently."""
        have = {}
        for view in self.views:
            images = self._image_frames(view)
            calibrated = self._calibrated.get(conv.drone_number(view), set())
            have[view] = (images, calibrated)
        out = {}
        for frame in sorted(set().union(*(a | b for a, b in have.values())) - set(self.frames)):
            lacking = [
                f'{v} {"/".join(w for w, s in (("image", a), ("calibration", b)) if frame not in s)}'
                for v, (a, b) in have.items()
                if frame not in a or frame not in b
            ]
            out[frame] = 'no ' + ', '.join(lacking)
        return out

    @cached_property
    def annotated_frames(self) -> tuple:
        folder = self.root / 'annotations_positions'
        return tuple(numbered_stems(folder, ('.json',))) if folder.is_dir() else ()

    @cached_property
    def trajectory_frames(self) -> tuple:
        """Frames with a ``matchings/Pedestrians/3d_TTTT.txt`` file (may be many more than ``frames``)."""
        folder = self.root / 'matchings/Pedestrians'
        if not folder.is_dir():
            return ()
        return tuple(sorted(int(p.stem[3:]) for p in folder.glob('3d_*.txt') if p.stem[3:].isdigit()))

    @property
    def area(self) -> tuple:
        return conv.area_from_file(*self.meta.get('area_file_xy', conv.ORIGINAL_AREA_FILE_XY))

    @cached_property
    def image_size(self) -> tuple:
        if 'image_size' in self.meta and not self.frames:
            return tuple(self.meta['image_size'])
        return super().image_size

    def image_path(self, view: str, frame: int) -> Path:
        return find_image(self.root / 'image_subsets' / view, f'{frame:04d}')

    # ----- calibration -----------------------------------------------------------------------------
    def _camera_from(self, folder: Path, view: str, frame: int, size: tuple) -> Camera:
        d = conv.drone_number(view)
        intr = read_matrices(
            folder / 'intrinsic' / f'intr_Drone{d}_{frame:04d}.xml', ['camera_matrix', 'distortion_coefficients']
        )
        extr = read_matrices(folder / 'extrinsic' / f'extr_Drone{d}_{frame:04d}.xml', ['rvec', 'tvec'])
        try:
            return conv.camera_from_file(
                intr['camera_matrix'], intr['distortion_coefficients'], extr['rvec'], extr['tvec'], *size
            )
        except ValueError as exc:
            raise DatasetError(f'{folder}: bad calibration of {view} frame {frame}: {exc}') from exc

    def camera(self, view: str, frame: int) -> Camera:
        return self._camera_cached(view, frame)

    @lru_cache(maxsize=4096)
    def _camera_cached(self, view: str, frame: int) -> Camera:
        return self._camera_from(self.root / 'calibrations', view, frame, self.image_size)

    @property
    def has_reference(self) -> bool:
        return (self.root / 'reference/calibrations/intrinsic').is_dir()

    def reference_image_path(self, view: str) -> Path:
        """Image of ``view`` at its reference pose (an empty scene in the real data)."""
        return find_image(self.root / 'reference/image_subsets' / view, '0000')

    def reference_image(self, view: str) -> np.ndarray:
        """(H, W, 3) BGR uint8 reference image of ``view``; :class:`DatasetError` if missing or undecodable."""
        return read_image(self.reference_image_path(view))

    def reference_camera(self, view: str) -> Camera:
        """Calibration of the reference image of ``view``."""
        size = image_size(self.reference_image_path(view))
        return self._camera_from(self.root / 'reference/calibrations', view, 0, size)

    # ----- annotations and trajectories ------------------------------------------------------------
    def position_to_world(self, position_id: int) -> np.ndarray:
        return conv.position_id_to_world(position_id)

    def world_to_position(self, xy) -> int:
        return conv.world_to_position_id(xy)

    def annotations(self, frame: int) -> list:
        path = self.root / 'annotations_positions' / f'{frame:04d}.json'
        if not path.is_file():
            return []
        try:
            entries = json.loads(path.read_text())
            persons = []
            for e in entries:
                boxes = {}
                for v in e['views']:
                    box = conv.box_from_file(v['xmin'], v['ymin'], v['xmax'], v['ymax'])
                    if box is not None:
                        boxes[conv.view_name(int(v['viewNum']) + 1)] = BoundingBox(*box)
                pid = int(e['positionID'])
                persons.append(PersonAnnotation(int(e['personID']), pid, self.position_to_world(pid), boxes))
        except (ValueError, KeyError, TypeError) as exc:
            raise DatasetError(f'malformed annotation file {path}: {exc!r}') from exc
        return persons

    def pedestrian_positions(self, frame: int) -> dict:
        """person id -> (3,) world metres from ``matchings/Pedestrians/3d_TTTT.txt`` (empty if absent)."""
        path = self.root / 'matchings/Pedestrians' / f'3d_{frame:04d}.txt'
        if not path.is_file():
            return {}
        table = _read_table(path, 5)
        xyz = conv.world_from_file(table[:, 2:5]) if len(table) else np.zeros((0, 3))
        return {int(i): p for i, p in zip(table[:, 0], xyz)}

    def line_of_sight(self, view: str, frame: int) -> set:
        """Person ids that the generator's line-of-sight test says ``view`` sees at ``frame``."""
        path = self.root / 'matchings/Pedestrians/LoS' / f'Drone{conv.drone_number(view)}_3d_{frame:04d}.txt'
        if not path.is_file():
            raise DatasetError(f'no line-of-sight file {path}')
        return {int(i) for i in _read_table(path, 5)[:, 0]}

    # ----- calibration markers ---------------------------------------------------------------------
    @cached_property
    def plane_markers(self) -> dict:
        """marker id -> (3,) world metres, from ``matchings/Planes/3d.txt`` (empty if absent)."""
        path = self.root / 'matchings/Planes/3d.txt'
        if not path.is_file():
            return {}
        table = _read_table(path, 5)
        return {int(i): p for i, p in zip(table[:, 1], conv.planes_3d_from_file(table[:, 2:5]))}

    @property
    def bogus_plane_frames(self) -> tuple:
        """Frames whose Planes 2-D files must not be used (frame 0 of the original generator)."""
        return tuple(self.meta.get('bogus_plane_frames', conv.ORIGINAL_BOGUS_PLANE_FRAMES))

    def plane_correspondences(self, view: str, frame: int):
        """Markers of ``3d.txt`` seen in ``view`` at ``frame`` as :class:`PlaneCorrespondences`.

        Returns None for frames listed in :attr:`bogus_plane_frames` or without a 2-D file. Ids not in
        ``3d.txt`` (pedestrians, board corners of unknown position) are left out.
        """
        path = self.root / 'matchings/Planes' / f'Camera{conv.drone_number(view)}_2d_{frame:04d}.txt'
        if frame in self.bogus_plane_frames or not path.is_file():
            return None
        table = _read_table(path, 4)
        keep = [i for i, mid in enumerate(table[:, 1].astype(np.int64)) if int(mid) in self.plane_markers]
        ids = table[keep, 1].astype(np.int64)
        return PlaneCorrespondences(
            ids,
            conv.pixels_from_file(table[keep, 2:4]).reshape(-1, 2),
            np.array([self.plane_markers[int(i)] for i in ids]).reshape(-1, 3),
        )
