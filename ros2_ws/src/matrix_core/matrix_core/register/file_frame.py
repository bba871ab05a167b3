"""The file form of a :class:`~matrix_core.register.registration.Registration`: the JSON record that
``matrix-tracker register`` writes per drone and frame, with its homographies in the MATRIX folder's own
file frame (raw image pixels, the calibration files' world), so that any MATRIX tool reads them. A site
dataset's calibration files are in the same file conventions, so its records are too.

Record keys: the scalar fields of the registration (``Registration.to_dict``) plus
``H_cur_to_ref`` (3x3: raw current-image pixels -> raw reference-image pixels) and ``H_img_to_ground``
(3x3: raw current-image pixels -> file world (x, y) metres on z = 0), both normalised to H[2, 2] = 1, or
null when the registration failed. The point conversions live in
:mod:`matrix_core.datasets.matrix_conventions`; here they are turned into the affine matrices that
re-express a homography.
"""

import json
from pathlib import Path

import numpy as np

from matrix_core.datasets import matrix_conventions as conv
from matrix_core.register.registration import Registration, RegistrationError, RegistrationStatus, check_homography


BROKEN_RECORD = ('unusable record', 'unreadable record')  # how a record file that cannot be used is reported


def record_name(view: str, frame: int) -> str:
    """File name of the record of drone ``view`` and ``frame`` in ``DIR/registration/``: 'Drone3_0017.json' for
    a MATRIX view name ('D3'), '<view>_0017.json' for any other drone name (a site dataset's: 'kestrel_0017.json')."""
    try:
        return f'Drone{conv.drone_number(view)}_{frame:04d}.json'
    except ValueError:
        return f'{view}_{frame:04d}.json'


def _affine_of(fn) -> np.ndarray:
    """(3, 3) matrix of an affine map of the plane, measured by applying ``fn`` ((N, 2) -> (N, 2))."""
    basis = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    out = np.asarray(fn(basis), dtype=np.float64)[:, :2]
    A = np.eye(3)
    A[:2, 2] = out[0]
    A[:2, 0] = out[1] - out[0]
    A[:2, 1] = out[2] - out[0]
    return A


def _normalised(H: np.ndarray) -> np.ndarray:
    return H / H[2, 2]


def registration_to_record(registration: Registration) -> dict:
    """Registration (internal frames) -> JSON-ready record with the homographies in the file frame."""
    record = registration.to_dict()
    record['H_cur_to_ref'] = record['H_img_to_ground'] = None
    if registration.ok:
        pix = _affine_of(conv.pixels_to_file)  # internal pixels -> file pixels
        world = _affine_of(conv.world_to_file)  # internal ground metres -> file ground metres
        record['H_cur_to_ref'] = _normalised(pix @ registration.ref_H_img @ np.linalg.inv(pix)).tolist()
        record['H_img_to_ground'] = _normalised(world @ registration.ground_H_img @ np.linalg.inv(pix)).tolist()
    return record


def registration_from_record(record: dict, where: str = 'record') -> Registration:
    """A record of :func:`registration_to_record` -> Registration in internal frames. A record that says
    ``ok`` but holds no usable homography comes back failed, saying why (``where`` names the file)."""
    values = {
        k: record.get(k, d)
        for k, d in (
            ('confidence', 0.0),
            ('matches', 0),
            ('inliers', 0),
            ('reference_id', ''),
            ('backend', ''),
            ('seconds', 0.0),
        )
    }
    error = record.get('inlier_error_px')
    values['inlier_error_px'] = float('nan') if error is None else float(error)
    if record.get('status') != str(RegistrationStatus.OK):
        try:
            status = RegistrationStatus.from_name(record.get('status'))
        except ValueError as exc:
            return Registration.failed(f'{where}: {exc}', **values)
        return Registration(status, message=record.get('message', '') or f'{where}: status {status}', **values)
    try:
        ground = check_homography(
            conv.ground_homography_from_file(
                check_homography(record.get('H_img_to_ground'), f'{where}: H_img_to_ground')
            ),
            f'{where}: H_img_to_ground',
        )
        pix = _affine_of(conv.pixels_to_file)
        ref = np.linalg.inv(pix) @ check_homography(record.get('H_cur_to_ref'), f'{where}: H_cur_to_ref') @ pix
    except (RegistrationError, TypeError) as exc:
        return Registration.failed(f'{BROKEN_RECORD[0]}: {exc}', **values)
    return Registration(
        RegistrationStatus.OK, _normalised(ref), _normalised(ground), message=record.get('message', ''), **values
    )


def read_registration(folder, view: str, frame: int):
    """The Registration of ``view`` and ``frame`` recorded in ``folder`` (``DIR/registration``), or None
    when there is no file. A file that cannot be read or parsed comes back failed, saying why."""
    path = Path(folder) / record_name(view, frame)
    if not path.is_file():
        return None
    try:
        record = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        return Registration.failed(f'{path}: {BROKEN_RECORD[1]}: {exc}')
    if not isinstance(record, dict):
        return Registration.failed(f'{path}: {BROKEN_RECORD[1]}: not a JSON object')
    try:
        return registration_from_record(record, str(path))
    except (TypeError, ValueError) as exc:  # e.g. a number field holding text
        return Registration.failed(f'{path}: {BROKEN_RECORD[1]}: {exc}')
