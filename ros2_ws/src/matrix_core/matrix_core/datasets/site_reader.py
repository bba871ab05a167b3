"""Reader of the site dataset format: a sequence of any site, with metric ground positions (no positionID grid).

Layout (``DIR/``; drone names and the site are those of ``DIR/site.yaml``; docs/site-file.md):

    site.yaml                           the site file; its references are the files under reference/
    site_dataset.json                   format name and version, image extension, generator (simulator config, seed)
    images/<drone>/TTTT.{png,jpg}       every drone's image of frame TTTT (4 digits, zero-padded)
    calibrations/<drone>/intr_TTTT.xml  per-frame calibration, the site file's matrix_xml pair (OpenCV XML in
    calibrations/<drone>/extr_TTTT.xml  MATRIX's file conventions, ``matrix_conventions`` converts)
    annotations/TTTT.json               [{"person_id": 3, "x": 1.25, "y": -4.5, "boxes": {"<drone>": [xmin, ymin,
                                        xmax, ymax]}}]: every person, metres in the internal world frame; a box
                                        (internal pixels, pixel-centre convention) for each drone that sees them
    boards/markers.txt                  "id x y z": every board inner corner, internal world metres
    boards/<drone>/TTTT.txt             "id u v": the corners that drone sees, internal pixels
    reference/<drone>/image.{png,jpg}   the drone's reference image (empty scene) ...
    reference/<drone>/intrinsic.xml     ... and its calibration (matrix_xml pair)
    reference/<drone>/extrinsic.xml

Every calibration is the site file's one format (``matrix_xml``), so the site file in the folder names its
references as any site does, and ``matrix-tracker site check DIR/site.yaml --require-references`` checks them.
"""

import json
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np

from matrix_core.datasets import matrix_conventions as conv
from matrix_core.datasets.base import MultiviewDataset, find_image, numbered_stems, read_image
from matrix_core.datasets.opencv_xml import read_matrices
from matrix_core.datasets.types import BoundingBox, DatasetError, PersonAnnotation, PlaneCorrespondences
from matrix_core.geometry.camera import Camera

FORMAT_NAME = 'site'
FORMAT_VERSION = 1
SITE_FILE = 'site.yaml'
META_FILE = 'site_dataset.json'
IMAGES, CALIBRATIONS, ANNOTATIONS, BOARDS, REFERENCE = 'images', 'calibrations', 'annotations', 'boards', 'reference'
NO_POSITION_ID = -1  # PersonAnnotation.position_id of a dataset without a ground grid


def intrinsic_name(frame: int) -> str:
    return f'intr_{frame:04d}.xml'


def extrinsic_name(frame: int) -> str:
    return f'extr_{frame:04d}.xml'


def read_matrix_xml(intrinsic: Path, extrinsic: Path, size: tuple) -> Camera:
    """The internal camera of a matrix_xml pair (``intr``: camera_matrix, distortion_coefficients; ``extr``:
    rvec, tvec) for images of ``size`` (w, h); :class:`DatasetError` naming the file when unusable."""
    intr = read_matrices(intrinsic, ['camera_matrix', 'distortion_coefficients'])
    extr = read_matrices(extrinsic, ['rvec', 'tvec'])
    try:
        return conv.camera_from_file(
            intr['camera_matrix'], intr['distortion_coefficients'], extr['rvec'], extr['tvec'], *size
        )
    except ValueError as exc:
        raise DatasetError(f'bad calibration {intrinsic} / {extrinsic}: {exc}') from exc


def _table(path: Path, columns: int) -> np.ndarray:
    try:
        rows = [line.split() for line in path.read_text().splitlines() if line.strip()]
        return np.array(rows, dtype=np.float64).reshape(-1, columns)
    except (OSError, ValueError) as exc:
        raise DatasetError(f'malformed table {path}: {exc}') from exc


class SiteDataset(MultiviewDataset):
    """A site dataset folder (module docstring). ``views`` are the site's drone names, in its order; ``frames``
    those with an image and a calibration of every drone; positions are metric (``area`` is the site's)."""

    format_name = FORMAT_NAME

    def __init__(self, root):
        super().__init__(root)
        from matrix_core.site.load import SiteError, load_site

        for name in (SITE_FILE, META_FILE):
            if not (self.root / name).is_file():
                raise DatasetError(f'{self.root} is not a site dataset: missing {name}')
        try:
            self.site = load_site(self.root / SITE_FILE)
        except SiteError as exc:
            raise DatasetError(str(exc)) from None
        path = self.root / META_FILE
        try:
            self.meta = json.loads(path.read_text())
        except ValueError as exc:
            raise DatasetError(f'malformed {path}: {exc}') from None
        if not isinstance(self.meta, dict) or self.meta.get('format') != FORMAT_NAME:
            raise DatasetError(f'{path}: not a site dataset (expected "format": "{FORMAT_NAME}")')
        if self.meta.get('version') != FORMAT_VERSION:
            raise DatasetError(
                f'{path}: this matrix-tracker reads version {FORMAT_VERSION}, got {self.meta.get("version")!r}'
            )

    # ----- structure -------------------------------------------------------------------------------
    @property
    def views(self) -> tuple:
        return self.site.drone_names

    @property
    def area(self) -> tuple:
        return self.site.area

    def _have(self, view: str) -> tuple:
        """(frames with an image, frames with both calibration files) of ``view``."""
        folder = self.root / IMAGES / view
        images = set(numbered_stems(folder)) if folder.is_dir() else set()
        cal = self.root / CALIBRATIONS / view
        calibrated = set()
        if cal.is_dir():
            for p in cal.glob('intr_*.xml'):
                stem = p.stem[5:]
                if stem.isdigit() and (cal / extrinsic_name(int(stem))).is_file():
                    calibrated.add(int(stem))
        return images, calibrated

    @cached_property
    def _frames_by_view(self) -> dict:
        return {v: self._have(v) for v in self.views}

    @cached_property
    def frames(self) -> tuple:
        sets = [a & b for a, b in self._frames_by_view.values()]
        return tuple(sorted(set.intersection(*sets))) if sets else ()

    @cached_property
    def incomplete_frames(self) -> dict:
        have = self._frames_by_view
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
        folder = self.root / ANNOTATIONS
        return tuple(numbered_stems(folder, ('.json',))) if folder.is_dir() else ()

    @property
    def trajectory_frames(self) -> tuple:
        """Frames with metric positions of every person (the annotated frames)."""
        return self.annotated_frames

    def image_path(self, view: str, frame: int) -> Path:
        self.view_index(view)
        return find_image(self.root / IMAGES / view, f'{frame:04d}')

    def view_image_size(self, view: str) -> tuple:
        """(width, height) of ``view``'s images: its camera's in the site file."""
        return self.site.drone(view).camera.image_size

    @cached_property
    def image_size(self) -> tuple:
        return self.view_image_size(self.views[0])

    # ----- calibration -----------------------------------------------------------------------------
    def camera(self, view: str, frame: int) -> Camera:
        return self._camera_cached(view, frame)

    @lru_cache(maxsize=4096)
    def _camera_cached(self, view: str, frame: int) -> Camera:
        folder = self.root / CALIBRATIONS / view
        return read_matrix_xml(
            folder / intrinsic_name(frame), folder / extrinsic_name(frame), self.view_image_size(view)
        )

    @property
    def has_reference(self) -> bool:
        from matrix_core.site.references import reference_files

        files = reference_files(self.site)
        return bool(files) and all(f.found for f in files)

    def reference_image_path(self, view: str) -> Path:
        from matrix_core.site.references import resolve

        drone = self.site.drone(view)
        if drone.reference is None:
            raise DatasetError(f'{self.root / SITE_FILE}: drone {view} has no reference')
        return resolve(self.site, drone.reference.image)

    def reference_image(self, view: str) -> np.ndarray:
        return read_image(self.reference_image_path(view))

    def reference_camera(self, view: str) -> Camera:
        from matrix_core.site.load import SiteError
        from matrix_core.site.references import reference_camera

        try:
            return reference_camera(self.site, self.site.drone(view))
        except SiteError as exc:
            raise DatasetError(str(exc)) from None

    # ----- annotations -----------------------------------------------------------------------------
    def position_to_world(self, position_id: int) -> np.ndarray:
        raise DatasetError(f'{self.root}: a site dataset has metric positions, no ground-grid ids')

    def annotations(self, frame: int) -> list:
        path = self.root / ANNOTATIONS / f'{frame:04d}.json'
        if not path.is_file():
            return []
        try:
            persons = []
            for e in json.loads(path.read_text()):
                boxes = {}
                for view, box in e['boxes'].items():
                    if view not in self.views:
                        raise ValueError(f'unknown drone {view!r}')
                    boxes[view] = BoundingBox(*(float(v) for v in box))
                xy = np.array([float(e['x']), float(e['y'])])
                if not np.isfinite(xy).all():
                    raise ValueError(f'person {e["person_id"]}: position is not finite')
                persons.append(PersonAnnotation(int(e['person_id']), NO_POSITION_ID, xy, boxes))
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise DatasetError(f'malformed annotation file {path}: {exc!r}') from exc
        return persons

    def pedestrian_positions(self, frame: int) -> dict:
        """person id -> (3,) metres (on the ground) of every annotated person of ``frame``."""
        return {a.person_id: np.array([a.world_xy[0], a.world_xy[1], 0.0]) for a in self.annotations(frame)}

    def line_of_sight(self, view: str, frame: int) -> set:
        """Person ids ``view`` sees at ``frame`` (those with a box in it)."""
        self.view_index(view)
        return {a.person_id for a in self.annotations(frame) if view in a.boxes}

    # ----- board corners ---------------------------------------------------------------------------
    @cached_property
    def plane_markers(self) -> dict:
        path = self.root / BOARDS / 'markers.txt'
        if not path.is_file():
            return {}
        table = _table(path, 4)
        return {int(r[0]): r[1:4].copy() for r in table}

    def plane_correspondences(self, view: str, frame: int):
        """The board corners ``view`` sees at ``frame`` as :class:`PlaneCorrespondences`, None without a file."""
        path = self.root / BOARDS / view / f'{frame:04d}.txt'
        if not path.is_file():
            return None
        table = _table(path, 3)
        keep = [i for i, mid in enumerate(table[:, 0].astype(np.int64)) if int(mid) in self.plane_markers]
        ids = table[keep, 0].astype(np.int64)
        return PlaneCorrespondences(
            ids, table[keep, 1:3].reshape(-1, 2), np.array([self.plane_markers[int(i)] for i in ids]).reshape(-1, 3)
        )
