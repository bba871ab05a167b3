"""Writer of the MATRIX folder format, the exact inverse of :mod:`matrix_reader` (used by the simulator
and by the calibration CLI). All file-convention conversions go through ``matrix_conventions``. Every file
is written under a temporary name and moved into place when complete (``output_paths``)."""

import json
from pathlib import Path

import cv2
import numpy as np

from matrix_core.datasets import matrix_conventions as conv
from matrix_core.datasets.matrix_reader import META_FILE
from matrix_core.datasets.opencv_xml import write_matrices
from matrix_core.geometry.camera import Camera
from matrix_core.output_paths import atomic_path, atomic_write_text


def _write_table(path: Path, rows, fmt: str) -> None:
    atomic_write_text(path, ''.join(fmt % tuple(r) + '\n' for r in rows) + '\n')


class MatrixWriter:
    """Writes a MATRIX-format folder under ``root``; every argument is in the internal convention.

    Args:
        root: output folder (created).
        area: (x_min, y_min, x_max, y_max) walkable area in internal world metres.
        image_ext: '.png' (lossless, default) or '.jpg'.
        extra_meta: more fields for ``matrix_tracker_meta.json`` (e.g. the simulator config and seed).
    """

    def __init__(self, root, area=None, image_ext: str = '.png', extra_meta: dict = None):
        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        if image_ext not in ('.png', '.jpg'):
            raise ValueError(f'image_ext must be .png or .jpg, got {image_ext!r}')
        self.image_ext = image_ext
        meta = {'generator': 'matrix-tracker', 'bogus_plane_frames': []}
        if area is not None:
            meta['area_file_xy'] = conv.area_to_file(area)
        meta.update(extra_meta or {})
        atomic_write_text(self.root / META_FILE, json.dumps(meta, indent=2, sort_keys=True) + '\n')

    def write_image(self, view: str, frame: int, image: np.ndarray, reference: bool = False) -> Path:
        """Write a (H, W, 3) BGR uint8 image of ``view`` at ``frame`` (or the view's reference image)."""
        base = self.root / 'reference' if reference else self.root
        path = base / 'image_subsets' / view / f'{frame:04d}{self.image_ext}'
        with atomic_path(path) as tmp:
            if not cv2.imwrite(str(tmp), image):
                raise OSError(f'cannot write image {path}')
        return path

    def write_camera(self, view: str, frame: int, camera: Camera, reference: bool = False) -> None:
        """Write ``intr_DroneN_TTTT.xml`` and ``extr_DroneN_TTTT.xml`` for ``camera``."""
        base = (self.root / 'reference' if reference else self.root) / 'calibrations'
        vals = conv.camera_to_file(camera)
        name = f'Drone{conv.drone_number(view)}_{frame:04d}.xml'
        write_matrices(
            base / 'intrinsic' / f'intr_{name}', {k: vals[k] for k in ('camera_matrix', 'distortion_coefficients')}
        )
        write_matrices(base / 'extrinsic' / f'extr_{name}', {k: vals[k] for k in ('rvec', 'tvec')})

    def write_annotations(self, frame: int, persons, views) -> None:
        """Write ``annotations_positions/TTTT.json``.

        Args:
            persons: :class:`PersonAnnotation` list (boxes only for visible views).
            views: all view names, in order; views without a box are written as invisible (-1).
        """
        entries = []
        for p in sorted(persons, key=lambda p: p.person_id):
            view_entries = []
            for view in views:
                box = p.boxes.get(view)
                fields = conv.INVISIBLE_BOX if box is None else conv.box_to_file(box.xmin, box.ymin, box.xmax, box.ymax)
                view_entries.append({'viewNum': conv.drone_number(view) - 1, **fields})
            entries.append({'personID': int(p.person_id), 'positionID': int(p.position_id), 'views': view_entries})
        path = self.root / 'annotations_positions' / f'{frame:04d}.json'
        atomic_write_text(path, json.dumps(entries, indent=4) + '\n')

    def _pedestrian_rows(self, positions: dict) -> list:
        rows = []
        for pid in sorted(positions):
            xyz = np.asarray(positions[pid], dtype=np.float64)
            pos_id = conv.world_to_position_id(xyz[:2])
            rows.append((pid, pos_id, *conv.world_to_file([xyz])[0]))
        return rows

    def write_pedestrians(self, frame: int, positions: dict) -> None:
        """Write ``matchings/Pedestrians/3d_TTTT.txt`` from person id -> (3,) world metres."""
        _write_table(
            self.root / 'matchings/Pedestrians' / f'3d_{frame:04d}.txt',
            self._pedestrian_rows(positions),
            '%d %d %f %f %f',
        )

    def write_line_of_sight(self, view: str, frame: int, positions: dict) -> None:
        """Write ``LoS/DroneN_3d_TTTT.txt``: the persons (id -> (3,) world metres) ``view`` sees."""
        path = self.root / 'matchings/Pedestrians/LoS' / f'Drone{conv.drone_number(view)}_3d_{frame:04d}.txt'
        _write_table(path, self._pedestrian_rows(positions), '%d %d %.2f %.2f %.2f')

    def write_plane_markers(self, markers: dict) -> None:
        """Write ``matchings/Planes/3d.txt`` from marker id -> (3,) world metres."""
        ids = sorted(markers)
        xyz = conv.planes_3d_to_file(np.array([markers[i] for i in ids]).reshape(-1, 3))
        _write_table(self.root / 'matchings/Planes/3d.txt', [(0, i, *p) for i, p in zip(ids, xyz)], '%d %d %f %f %f')

    def write_plane_points(self, view: str, frame: int, marker_ids, image_uv) -> None:
        """Write ``matchings/Planes/CameraN_2d_TTTT.txt``: (N,) ids and (N, 2) internal pixels."""
        uv = conv.pixels_to_file(np.asarray(image_uv).reshape(-1, 2))
        path = self.root / 'matchings/Planes' / f'Camera{conv.drone_number(view)}_2d_{frame:04d}.txt'
        _write_table(path, [(0, int(i), *p) for i, p in zip(marker_ids, uv)], '%d %d %f %f')
