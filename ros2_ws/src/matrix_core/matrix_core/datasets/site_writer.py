"""Writer of the site dataset format (layout in :mod:`matrix_core.datasets.site_reader`), its exact inverse.

The folder's ``site.yaml`` is the site document given to the writer with its references set to the files the
writer puts under ``reference/`` (``references: {source: files, root: .}``: relative to the site file, so the
folder can be moved or copied whole). It is checked by the site loader as soon as it is written. Every file is
written under a temporary name and moved into place when complete (``output_paths``).
"""

import copy
import json
from pathlib import Path

import cv2
import numpy as np
import yaml

from matrix_core.datasets import matrix_conventions as conv
from matrix_core.datasets import site_reader as layout
from matrix_core.datasets.opencv_xml import write_matrices
from matrix_core.geometry.camera import Camera
from matrix_core.output_paths import atomic_path, atomic_write_text


def _write_matrix_xml(intrinsic: Path, extrinsic: Path, camera: Camera) -> None:
    vals = conv.camera_to_file(camera)
    write_matrices(intrinsic, {k: vals[k] for k in ('camera_matrix', 'distortion_coefficients')})
    write_matrices(extrinsic, {k: vals[k] for k in ('rvec', 'tvec')})


def _rows(path: Path, rows, fmt: str) -> None:
    atomic_write_text(path, ''.join(fmt % tuple(r) + '\n' for r in rows))


class SiteDatasetWriter:
    """Writes a site dataset under ``root``; every argument is in the internal convention.

    Args:
        root: output folder (created).
        site_document: the site file's content (a dict as its YAML holds it) without ``references`` and
            without the drones' ``reference`` entries: the writer sets them.
        image_ext: '.png' (lossless, default) or '.jpg'.
        extra_meta: more fields for ``site_dataset.json`` (e.g. the simulator config and seed).
    """

    def __init__(self, root, site_document: dict, image_ext: str = '.png', extra_meta: dict = None):
        from matrix_core.site.load import load_site

        self.root = Path(root)
        self.root.mkdir(parents=True, exist_ok=True)
        if image_ext not in ('.png', '.jpg'):
            raise ValueError(f'image_ext must be .png or .jpg, got {image_ext!r}')
        self.image_ext = image_ext
        doc = copy.deepcopy(site_document)
        doc['references'] = {'source': 'files', 'root': '.'}
        for drone in doc['drones']:
            drone['reference'] = self.reference_entry(drone['name'])
        self.views = tuple(d['name'] for d in doc['drones'])
        header = (
            '# Written by matrix-tracker with the dataset beside it (docs/site-file.md). Its references are the\n'
            '# reference/ files of this folder (root: . is this file\'s folder).\n'
        )
        path = self.root / layout.SITE_FILE
        atomic_write_text(path, header + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=110))
        self.site = load_site(path)  # the document is a valid site file, before any frame is written
        meta = {'format': layout.FORMAT_NAME, 'version': layout.FORMAT_VERSION, 'generator': 'matrix-tracker'}
        meta.update({'image_ext': image_ext, **(extra_meta or {})})
        atomic_write_text(self.root / layout.META_FILE, json.dumps(meta, indent=2, sort_keys=True) + '\n')

    def reference_entry(self, drone: str) -> dict:
        """The ``reference`` entry of a drone in ``site.yaml`` (paths relative to the dataset folder)."""
        base = f'{layout.REFERENCE}/{drone}'
        return {
            'image': f'{base}/image{self.image_ext}',
            'calibration': {
                'format': 'matrix_xml',
                'intrinsic': f'{base}/intrinsic.xml',
                'extrinsic': f'{base}/extrinsic.xml',
            },
        }

    def _check_view(self, view: str) -> None:
        if view not in self.views:
            raise ValueError(f'{self.root}: no drone {view!r} in the site (drones: {", ".join(self.views)})')

    def write_image(self, view: str, frame: int, image: np.ndarray) -> Path:
        """Write a (H, W, 3) BGR uint8 image of ``view`` at ``frame``."""
        self._check_view(view)
        return self._image(self.root / layout.IMAGES / view / f'{frame:04d}{self.image_ext}', image)

    def _image(self, path: Path, image: np.ndarray) -> Path:
        with atomic_path(path) as tmp:
            if not cv2.imwrite(str(tmp), image):
                raise OSError(f'cannot write image {path}')
        return path

    def write_camera(self, view: str, frame: int, camera: Camera) -> None:
        """Write ``calibrations/<view>/{intr,extr}_TTTT.xml`` of ``camera``."""
        self._check_view(view)
        folder = self.root / layout.CALIBRATIONS / view
        _write_matrix_xml(folder / layout.intrinsic_name(frame), folder / layout.extrinsic_name(frame), camera)

    def write_reference(self, view: str, image: np.ndarray, camera: Camera) -> None:
        """Write the reference image and calibration of ``view`` (the files ``site.yaml`` names)."""
        self._check_view(view)
        folder = self.root / layout.REFERENCE / view
        self._image(folder / f'image{self.image_ext}', image)
        _write_matrix_xml(folder / 'intrinsic.xml', folder / 'extrinsic.xml', camera)

    def write_annotations(self, frame: int, positions: dict, boxes: dict) -> None:
        """Write ``annotations/TTTT.json`` from person id -> (2+,) metres and person id -> {view: BoundingBox}
        (views that see the person)."""
        entries = []
        for pid in sorted(positions):
            xy = np.asarray(positions[pid], dtype=np.float64)[:2]
            view_boxes = {}
            for view, b in sorted((boxes.get(pid) or {}).items(), key=lambda kv: self.views.index(kv[0])):
                self._check_view(view)
                view_boxes[view] = [round(float(v), 3) for v in (b.xmin, b.ymin, b.xmax, b.ymax)]
            entries.append(
                {'person_id': int(pid), 'x': round(float(xy[0]), 4), 'y': round(float(xy[1]), 4), 'boxes': view_boxes}
            )
        atomic_write_text(self.root / layout.ANNOTATIONS / f'{frame:04d}.json', json.dumps(entries, indent=1) + '\n')

    def write_board_markers(self, markers: dict) -> None:
        """Write ``boards/markers.txt`` from marker id -> (3,) metres."""
        _rows(
            self.root / layout.BOARDS / 'markers.txt', [(i, *markers[i]) for i in sorted(markers)], '%d %.6f %.6f %.6f'
        )

    def write_board_points(self, view: str, frame: int, marker_ids, image_uv) -> None:
        """Write ``boards/<view>/TTTT.txt``: (N,) marker ids and (N, 2) internal pixels."""
        self._check_view(view)
        uv = np.asarray(image_uv, dtype=np.float64).reshape(-1, 2)
        _rows(
            self.root / layout.BOARDS / view / f'{frame:04d}.txt',
            [(int(i), *p) for i, p in zip(marker_ids, uv)],
            '%d %.4f %.4f',
        )


class SiteCalibrationWriter:
    """Writes per-frame calibrations of a site dataset's frames (``matrix-tracker calibrate``) under ``root`` as
    a site dataset of their own: ``site.yaml`` (the source's site, its references those of the source, by
    absolute ``references.root``), ``site_dataset.json``, ``calibrations/<drone>/{intr,extr}_TTTT.xml`` and
    links to the source images in ``images/<drone>/``, so that ``open_dataset(root)`` reads it as any site
    dataset."""

    def __init__(self, root, source, extra_meta: dict = None):
        from matrix_core.site.references import reference_root

        self.root, self.source = Path(root), source
        self.root.mkdir(parents=True, exist_ok=True)
        doc = yaml.safe_load((source.root / layout.SITE_FILE).read_text())
        doc['references'] = {'source': 'files', 'root': str(reference_root(source.site))}
        where = source.root.resolve()
        header = f'# Written by matrix-tracker calibrate from {where}; its references are that folder\'s.\n'
        atomic_write_text(self.root / layout.SITE_FILE, header + yaml.safe_dump(doc, sort_keys=False, width=110))
        meta = {'format': layout.FORMAT_NAME, 'version': layout.FORMAT_VERSION, 'generator': 'matrix-tracker'}
        meta.update({'image_ext': source.meta.get('image_ext', '.png'), **(extra_meta or {})})
        atomic_write_text(self.root / layout.META_FILE, json.dumps(meta, indent=2, sort_keys=True) + '\n')

    def write_camera(self, view: str, frame: int, camera: Camera) -> None:
        """Write ``calibrations/<view>/{intr,extr}_TTTT.xml`` of ``camera``."""
        folder = self.root / layout.CALIBRATIONS / view
        _write_matrix_xml(folder / layout.intrinsic_name(frame), folder / layout.extrinsic_name(frame), camera)

    def image_link(self, view: str, frame: int) -> tuple:
        """(the source image of ``view`` at ``frame``, the path its link takes under ``root``)."""
        src = self.source.image_path(view, frame).resolve()
        return src, self.root / layout.IMAGES / view / src.name
