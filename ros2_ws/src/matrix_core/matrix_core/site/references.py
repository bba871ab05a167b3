"""A site's reference images and calibrations on disk: where they are, which exist, and reading them.

A site file names each drone's reference relative to ``references.root`` (itself relative to the site file's
folder, and may contain ``${NAME}`` environment variables: the shipped MATRIX site uses
``${MATRIX_SHARED}/matrix_sample``). Loading a site never reads these files; a command that needs them calls
:func:`require_references` first, so that it stops before it starts, naming the drone and the file.
"""

from dataclasses import dataclass
from pathlib import Path

from matrix_core.geometry.camera import Camera
from matrix_core.site.load import SiteError, expand_variables
from matrix_core.site.schema import CalibrationFormat, DroneSpec, ReferenceSource, Site


def reference_root(site: Site) -> Path:
    """The folder the drones' reference paths are relative to; SiteError naming an unset variable."""
    if site.references_root is None:
        _, missing = expand_variables(site.references_root_text)
        raise SiteError(
            f'{site.path}: references.root: {site.references_root_text!r} names the environment variable '
            f'{missing}, which is not set'
        )
    return site.references_root


def resolve(site: Site, path: Path) -> Path:
    """A reference path of the site file (relative to ``references.root``, or absolute) as an absolute path."""
    return (reference_root(site) / path).resolve()


@dataclass(frozen=True)
class ReferenceFiles:
    """One drone's reference files and which of them are missing (absolute paths)."""

    drone: str
    image: Path
    calibration: tuple
    missing: tuple

    @property
    def found(self) -> bool:
        return not self.missing


def reference_files(site: Site) -> list:
    """:class:`ReferenceFiles` of every drone (empty when the references are to be simulated)."""
    if site.references is ReferenceSource.SIMULATE:
        return []
    out = []
    for d in site.drones:
        image = resolve(site, d.reference.image)
        calibration = tuple(resolve(site, p) for p in d.reference.calibration.files)
        missing = tuple(p for p in (image, *calibration) if not p.is_file())
        out.append(ReferenceFiles(d.name, image, calibration, missing))
    return out


def _key(site: Site, drone: str) -> str:
    """How an error names a drone's entry: ``drones[2] (P3)``."""
    return f'drones[{site.drone_names.index(drone)}] ({drone})'


def reference_camera(site: Site, drone: DroneSpec) -> Camera:
    """The calibration of ``drone``'s reference image, in the internal conventions; SiteError when unreadable."""
    from matrix_core.datasets import matrix_conventions as conv
    from matrix_core.datasets.opencv_xml import read_matrices
    from matrix_core.datasets.types import DatasetError

    if drone.reference is None:
        raise SiteError(f'{site.path}: {_key(site, drone.name)}: no reference (references.source is simulate)')
    cal = drone.reference.calibration
    if cal.format is CalibrationFormat.CAMERA_YAML:
        return _camera_yaml(site, drone)
    if cal.format is not CalibrationFormat.MATRIX_XML:
        raise SiteError(f'{site.path}: {_key(site, drone.name)}: cannot read calibration format {cal.format.value}')
    try:
        intr = read_matrices(resolve(site, cal.intrinsic), ['camera_matrix', 'distortion_coefficients'])
        extr = read_matrices(resolve(site, cal.extrinsic), ['rvec', 'tvec'])
        return conv.camera_from_file(
            intr['camera_matrix'], intr['distortion_coefficients'], extr['rvec'], extr['tvec'], *drone.camera.image_size
        )
    except (DatasetError, ValueError) as exc:
        raise SiteError(f'{site.path}: {_key(site, drone.name)}.reference.calibration: {exc}') from None


def _camera_yaml(site: Site, drone: DroneSpec) -> Camera:
    """The ``camera_yaml`` calibration of ``drone``'s reference (schema.CalibrationFormat)."""
    import numpy as np

    from matrix_core.settings import read_yaml

    cal = drone.reference.calibration
    where = f'{site.path}: {_key(site, drone.name)}.reference.calibration'
    try:
        intr, extr = read_yaml(resolve(site, cal.intrinsic)), read_yaml(resolve(site, cal.extrinsic))
        size = tuple(int(v) for v in intr['image_size'])
        if size != tuple(drone.camera.image_size):
            raise ValueError(
                f'intrinsic image_size {list(size)} is not camera.image_size {list(drone.camera.image_size)}'
            )
        K = np.asarray(intr['K'], float).reshape(3, 3)
        return Camera(K, np.asarray(extr['cam_T_world'], float).reshape(4, 4), *size, np.asarray(intr['dist'], float))
    except (KeyError, TypeError, ValueError, FileNotFoundError) as exc:
        raise SiteError(f'{where}: {type(exc).__name__ if isinstance(exc, KeyError) else ""}{exc}') from None


def require_references(site: Site) -> None:
    """Check that every drone's reference image and calibration exist and that each image has the drone's
    ``camera.image_size``: SiteError naming the first fault (the drone, the key and the file), else nothing."""
    from matrix_core.datasets.base import image_size
    from matrix_core.datasets.types import DatasetError

    if site.references is ReferenceSource.SIMULATE:
        raise SiteError(
            f'{site.path}: references.source: simulate: this site has no reference images or calibrations yet, '
            f'and this command needs them'
        )
    for files in reference_files(site):
        if files.missing:
            raise SiteError(f'{site.path}: {_key(site, files.drone)}.reference: no such file {files.missing[0]}')
        drone = site.drone(files.drone)
        try:
            size = tuple(image_size(files.image))
        except DatasetError as exc:
            raise SiteError(f'{site.path}: {_key(site, drone.name)}.reference.image: {exc}') from None
        if size != drone.camera.image_size:
            raise SiteError(
                f'{site.path}: {_key(site, drone.name)}.reference.image: {files.image} is {size[0]}x{size[1]}, '
                f'camera.image_size is {drone.camera.image_size[0]}x{drone.camera.image_size[1]}'
            )
        reference_camera(site, drone)


class SiteReferences:
    """A site's references read the way the nodes read a dataset folder's (``reference_image``,
    ``reference_camera``, ``has_reference``, ``views``, ``area``, ``root``), so that a site file is a node's
    source of references without any dataset folder beside it (``datasets.drone_inputs.open_references``).
    A drone's unreadable file is a :class:`~matrix_core.datasets.types.DatasetError` naming the drone and the
    file, as a folder's would be."""

    meta = None  # a site states its obstacles in the site file, not in a dataset's meta

    def __init__(self, site: Site):
        if site.references is ReferenceSource.SIMULATE:
            raise SiteError(
                f'{site.path}: references.source: simulate: this site has no reference images or calibrations '
                f'yet (matrix-tracker simulate --site writes a site dataset whose site.yaml has them)'
            )
        self.site = site
        self.root = site.path

    @property
    def views(self) -> tuple:
        return self.site.drone_names

    @property
    def area(self) -> tuple:
        return self.site.area

    @property
    def has_reference(self) -> bool:
        return True

    def _drone(self, view: str) -> DroneSpec:
        from matrix_core.datasets.types import DatasetError

        if view not in self.site.drone_names:
            raise DatasetError(f'{self.site.path}: no drone {view!r} (its drones: {", ".join(self.site.drone_names)})')
        return self.site.drone(view)

    def reference_image(self, view: str):
        """(H, W, 3) BGR reference image of ``view``, checked to have its camera's image size."""
        from matrix_core.datasets.base import read_image
        from matrix_core.datasets.types import DatasetError

        drone = self._drone(view)
        try:
            image = read_image(resolve(self.site, drone.reference.image))
        except SiteError as exc:
            raise DatasetError(str(exc)) from None
        size = (image.shape[1], image.shape[0])
        if size != tuple(drone.camera.image_size):
            raise DatasetError(
                f'{self.site.path}: {_key(self.site, view)}.reference.image is {size[0]}x{size[1]}, '
                f'camera.image_size is {drone.camera.image_size[0]}x{drone.camera.image_size[1]}'
            )
        return image

    def reference_camera(self, view: str) -> Camera:
        from matrix_core.datasets.types import DatasetError

        try:
            return reference_camera(self.site, self._drone(view))
        except SiteError as exc:
            raise DatasetError(str(exc)) from None
