"""Where each frame's image-to-ground homography comes from when lifting features (a registry).

Each provider is ``factory(dataset, frames) -> homography_of(view, frame) -> (img_H_ground (3, 3), (w, h))``
(``img_H_ground`` maps world metres on z = 0 to full-resolution image pixels, any overall scale/sign):
    - ``ground_truth``: the dataset's per-frame calibration (moving drones, perfect calibration);
    - ``frozen_first``: the calibration of the first frame of the sequence for every frame (the
      static-camera assumption of EarlyBird/TrackTacular applied to moving drones);
    - ``reference``: the dataset's reference calibration of each drone (MATRIX ``reference/``).
Per-frame PnP (``matrix_core.calib``: its Camera's ``img_H_ground()``) and registration
(``matrix_core.register``: ``img_H_ref @ reference_camera.img_H_ground()``) plug in as further entries.
"""

from matrix_core.datasets.types import DatasetError


def _from_cameras(camera_of):
    def homography_of(view, frame):
        cam = camera_of(view, frame)
        return cam.img_H_ground(), (cam.width, cam.height)
    return homography_of


def _ground_truth(dataset, frames):
    return _from_cameras(dataset.camera)


def _frozen_first(dataset, frames):
    if not frames:
        raise DatasetError('frozen_first calibration needs at least one frame')
    first = min(frames)
    return _from_cameras(lambda view, frame: dataset.camera(view, first))


def _reference(dataset, frames):
    if not getattr(dataset, 'has_reference', False):
        raise DatasetError(f'{dataset.root} has no reference/ calibration')
    cams = {v: dataset.reference_camera(v) for v in dataset.views}
    return _from_cameras(lambda view, frame: cams[view])


CALIBRATION_SOURCES = {'ground_truth': _ground_truth, 'frozen_first': _frozen_first, 'reference': _reference}


def calibration_source(name: str, dataset, frames):
    """``homography_of(view, frame)`` of the named source; ValueError lists the known names."""
    try:
        factory = CALIBRATION_SOURCES[name]
    except KeyError:
        raise ValueError(f'unknown calibration source {name!r}; known: {sorted(CALIBRATION_SOURCES)}') from None
    return factory(dataset, tuple(frames))
