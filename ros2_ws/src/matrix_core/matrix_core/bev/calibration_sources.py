"""Where each frame's image-to-ground homography comes from when lifting features (a registry).

Each provider is ``factory(dataset, frames, calibration_dir) -> homography_of(view, frame)``, which returns
``(img_H_ground (3, 3), (w, h))`` (``img_H_ground`` maps world metres on z = 0 to full-resolution image
pixels of the internal convention, any overall scale/sign) or ``None`` when the source has no result for
that view and frame: the view is then masked for that frame, nothing is invented.
    - ``ground_truth``: the dataset's per-frame calibration (moving drones, perfect calibration);
    - ``frozen_first``: the calibration of the first frame of the sequence for every frame (the
      static-camera assumption of EarlyBird/TrackTacular applied to moving drones);
    - ``reference``: the dataset's reference calibration of each drone (MATRIX ``reference/``);
    - ``pnp``: per-frame checkerboard PnP written by ``matrix-tracker calibrate DATASET --out DIR``
      (``DIR/calibrations`` + ``DIR/calibration_status.csv``); only frames with status ``ok`` are used;
    - ``pnp_stale``: the same, also using ``stale`` frames (the calibrator's last good pose, as the live
      ``calib`` node republishes it; written only by ``calibrate --write-stale``);
    - ``registration``: ``DIR/registration/Drone{N}_{TTTT}.json`` of ``matrix-tracker register DATASET
      --out DIR`` (read by ``register.file_frame``: the registration contract's file form);
      frames whose status is not ``ok`` are masked.

A result file that exists but cannot be used (malformed XML, NaN or singular matrices, a record that says ok
without a usable homography) raises :class:`DatasetError` saying why; ``BevFrames`` masks that view for that
frame and keeps the reason.
"""

import csv
from pathlib import Path


from matrix_core.calib.status import CalibStatus
from matrix_core.datasets.types import DatasetError
from matrix_core.datasets.matrix_conventions import drone_number
from matrix_core.register.file_frame import BROKEN_RECORD, read_registration


def _from_cameras(camera_of):
    def homography_of(view, frame):
        cam = camera_of(view, frame)
        return None if cam is None else (cam.img_H_ground(), (cam.width, cam.height))

    return homography_of


def _ground_truth(dataset, frames, calibration_dir):
    return _from_cameras(dataset.camera)


def _frozen_first(dataset, frames, calibration_dir):
    if not frames:
        raise DatasetError('frozen_first calibration needs at least one frame')
    first = min(frames)
    return _from_cameras(lambda view, frame: dataset.camera(view, first))


def _reference(dataset, frames, calibration_dir):
    if not getattr(dataset, 'has_reference', False):
        raise DatasetError(f'{dataset.root} has no reference/ calibration')
    cams = {v: dataset.reference_camera(v) for v in dataset.views}
    return _from_cameras(lambda view, frame: cams[view])


def _need_dir(name: str, calibration_dir, sub: str) -> Path:
    if calibration_dir is None:
        raise ValueError(
            f'calibration source {name!r} needs calibration_dir (the --out DIR of '
            f'matrix-tracker {"calibrate" if name.startswith("pnp") else "register"})'
        )
    path = Path(calibration_dir)
    if not (path / sub).is_dir():
        raise DatasetError(f'{path} has no {sub}/ (calibration source {name!r})')
    return path


def _pnp_statuses(path: Path) -> dict:
    """(view, frame) -> :class:`CalibStatus` from ``calibration_status.csv``; {} when the file is absent; a
    status it does not know is a DatasetError naming the file."""
    status_file = path / 'calibration_status.csv'
    if not status_file.is_file():
        return {}
    with open(status_file, newline='') as fh:
        try:
            return {(r['view'], int(r['frame'])): CalibStatus.from_name(r['status']) for r in csv.DictReader(fh)}
        except ValueError as exc:
            raise DatasetError(f'{status_file}: {exc}') from exc


def _pnp_factory(accepted: tuple, name: str):
    def factory(dataset, frames, calibration_dir):
        path = _need_dir(name, calibration_dir, 'calibrations/extrinsic')
        statuses = _pnp_statuses(path)
        size = dataset.image_size

        def camera_of(view, frame):
            if statuses and statuses.get((view, frame)) not in accepted:
                return None
            if not (path / 'calibrations/extrinsic' / f'extr_Drone{drone_number(view)}_{frame:04d}.xml').is_file():
                return None  # no file written: calibrate had no result for this view and frame
            # the same MATRIX reader as the dataset's, on DIR's calibration files; a broken file raises
            return dataset._camera_from(path / 'calibrations', view, frame, size)

        return _from_cameras(camera_of)

    return factory


def _registration(dataset, frames, calibration_dir):
    path = _need_dir('registration', calibration_dir, 'registration')
    size = dataset.image_size

    def homography_of(view, frame):
        registration = read_registration(path / 'registration', view, frame)
        if registration is None:
            return None
        if registration.ok:
            return registration.img_H_ground, size
        if any(m in registration.message for m in BROKEN_RECORD):  # a file that said ok holds no usable homography
            raise DatasetError(registration.message)
        return None  # register failed this frame: no result

    return homography_of


CALIBRATION_SOURCES = {
    'ground_truth': _ground_truth,
    'frozen_first': _frozen_first,
    'reference': _reference,
    'pnp': _pnp_factory((CalibStatus.OK,), 'pnp'),
    'pnp_stale': _pnp_factory((CalibStatus.OK, CalibStatus.STALE), 'pnp_stale'),
    'registration': _registration,
}


def calibration_source(name: str, dataset, frames, calibration_dir=None):
    """``homography_of(view, frame)`` of the named source (None where it has no result); ValueError lists
    the known names. ``calibration_dir``: the output folder of calibrate/register for pnp/registration."""
    try:
        factory = CALIBRATION_SOURCES[name]
    except KeyError:
        raise ValueError(f'unknown calibration source {name!r}; known: {sorted(CALIBRATION_SOURCES)}') from None
    return factory(dataset, tuple(frames), calibration_dir)
