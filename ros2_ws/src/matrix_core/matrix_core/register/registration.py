"""The registration contract: what one drone frame's registration to its reference says, for every consumer.

``register`` (the node and the CLI) produces a :class:`Registration`; ``fuse`` lifts features with its
``img_H_ground``, ``calib`` predicts the boards with the camera it implies, the graph monitor scores it and
the offline calibration sources read it back from files. The message form is
``matrix_msgs/HomographyStamped`` (conversion in :mod:`matrix_core.message_fields`), the file form the JSON
of ``matrix-tracker register`` (``matrix_core.cli.register``).

Convention (``a_H_b`` maps frame ``b`` to ``a``; pixels are full-resolution, OpenCV pixel centres):
    ``ref_H_img`` (3, 3): current-image pixels -> reference-image pixels;
    ``ground_H_img`` (3, 3): current-image pixels -> world ground metres (x, y on z = 0),
    ``ground_H_img = ref_camera.ground_H_img() @ ref_H_img``; both normalised so that H[2, 2] = 1.

Validity, one rule: a registration is usable when its status is ``OK`` and ``ground_H_img`` is a finite,
non-singular 3x3 matrix (:func:`check_homography`). A failed registration carries no matrices (None), never
NaN or zero sentinels; its ``message`` says why. A registration read from a message or file that said ``OK``
but breaks the rule has status ``UNUSABLE`` (register did not fail; the data is bad).
"""

import enum
from dataclasses import dataclass, field

import numpy as np

from matrix_core.geometry.homography import ImpliedCamera, implied_camera


class RegistrationStatus(enum.IntEnum):
    """What one registration says. The values are ``matrix_msgs/HomographyStamped``'s status constants; the
    lower-case names are the file form (``to_dict``) and what logs and diagnostics print."""

    OK = 0
    FAILED = 1  # register could not register the frame: too few inliers, no fit, rejected by the gate (message: why)
    BAD_INPUT = 2  # the image, or what should become the reference, could not be used at all (message: why)
    UNUSABLE = 3  # it said OK, but what arrived breaks the validity rule (message: why)

    def __str__(self) -> str:
        return self.name.lower()

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)

    @classmethod
    def from_name(cls, name: str) -> 'RegistrationStatus':
        """The status whose lower-case name is ``name`` (the file form); ValueError naming the valid ones."""
        try:
            return cls[str(name).upper()]
        except KeyError:
            raise ValueError(f'unknown registration status {name!r}; one of {", ".join(map(str, cls))}') from None


# Below this reciprocal condition number a homography is numerically singular (its inverse would invent geometry).
MIN_RCOND = 1e-12


class RegistrationError(ValueError):
    """A registration cannot be used (failed, or its homography is not finite / singular); says why."""


def check_homography(H, what: str = 'homography') -> np.ndarray:
    """The one validity rule of a homography: (3, 3), finite, not singular. Returns it as float64 (3, 3);
    raises :class:`RegistrationError` naming ``what`` otherwise."""
    H = np.asarray(H, dtype=np.float64)
    if H.size != 9:
        raise RegistrationError(f'{what} needs 9 values, got {H.size}')
    H = H.reshape(3, 3)
    if not np.all(np.isfinite(H)):
        raise RegistrationError(f'{what} has NaN/infinite values')
    if np.linalg.cond(H) > 1 / MIN_RCOND:
        raise RegistrationError(f'{what} is singular')
    return H


@dataclass(frozen=True)
class Registration:
    """Registration of one current image to its drone's reference image.

    Attributes:
        status: :class:`RegistrationStatus` (``OK``, or why not).
        ref_H_img: (3, 3) current pixels -> reference pixels, or None unless ok.
        ground_H_img: (3, 3) current pixels -> ground metres, or None unless ok.
        confidence: inliers / matches (0 without matches).
        matches: symmetric ratio-test matches; inliers: robust-fit inliers among them.
        inlier_error_px: mean inlier reprojection error in full-resolution reference pixels (NaN if none).
        reference_id: the reference the homography is chained through (e.g. 'D1/reference' or
            'D1/reference<-key:17' after re-keying).
        backend: feature backend name; seconds: wall time of the registration.
        message: why it failed, or what happened (re-keying, retrying the reference); '' otherwise.
        implied: the rigid camera ``ground_H_img`` implies with the reference's intrinsics, as the sanity
            gate computed it (None when not computed yet: :meth:`implied_camera` computes it once).
    """

    status: RegistrationStatus
    ref_H_img: np.ndarray = None
    ground_H_img: np.ndarray = None
    confidence: float = 0.0
    matches: int = 0
    inliers: int = 0
    inlier_error_px: float = float('nan')
    reference_id: str = ''
    backend: str = ''
    seconds: float = 0.0
    message: str = ''
    implied: ImpliedCamera = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def failed(cls, reason: str, **values) -> 'Registration':
        """A failed registration (no matrices) saying ``reason``."""
        return cls(RegistrationStatus.FAILED, message=reason, **values)

    @classmethod
    def bad_input(cls, reason: str, **values) -> 'Registration':
        """A registration of input that could not be used at all (no matrices), saying ``reason``."""
        return cls(RegistrationStatus.BAD_INPUT, message=reason, **values)

    @classmethod
    def from_img_H_ground(cls, img_H_ground, **values) -> 'Registration':
        """An ``ok`` registration known only by its (3, 3) ``img_H_ground`` (ground metres -> pixels), e.g. a
        calibration or a test's prior; ``ref_H_img`` stays None. A non-invertible one is ``unusable``."""
        try:
            ground_H_img = np.linalg.inv(check_homography(img_H_ground, 'img_H_ground'))
        except RegistrationError as exc:
            return cls(RegistrationStatus.UNUSABLE, message=str(exc), **values)
        return cls(RegistrationStatus.OK, None, ground_H_img / ground_H_img[2, 2], **values)

    @property
    def ok(self) -> bool:
        return self.status == RegistrationStatus.OK

    @property
    def implied_center(self):
        """(3,) world metres of the camera centre the gate's implied camera has, or None."""
        return None if self.implied is None else self.implied.center

    @property
    def img_H_ground(self) -> np.ndarray:
        """(3, 3) ground metres -> current pixels (the inverse of ``ground_H_img``), for lifting and prediction.
        Raises :class:`RegistrationError` when the registration is not usable (see the module docstring)."""
        if 'img_H_ground' not in self._cache:
            if not self.ok:
                raise RegistrationError(f'registration {self.status}: {self.message}')
            self._cache['img_H_ground'] = np.linalg.inv(check_homography(self.ground_H_img, 'ground_H_img'))
        return self._cache['img_H_ground']

    def implied_camera(self, K: np.ndarray) -> ImpliedCamera:
        """The rigid camera (intrinsics ``K`` (3, 3)) that ``img_H_ground`` implies: the gate's when it used the
        same ``K``, else computed once and kept. Raises :class:`RegistrationError` when not usable."""
        K = np.asarray(K, dtype=np.float64)
        for known in (self.implied, self._cache.get('implied')):
            if known is not None and known.K is not None and np.array_equal(known.K, K):
                return known
        self._cache['implied'] = implied = implied_camera(K, self.img_H_ground)
        return implied

    def to_dict(self) -> dict:
        """JSON-ready dict of the scalar fields (the matrices' file form: ``register.file_frame``)."""

        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)

        return {
            'status': str(self.status),
            'confidence': float(self.confidence),
            'matches': int(self.matches),
            'inliers': int(self.inliers),
            'inlier_error_px': num(self.inlier_error_px),
            'reference_id': self.reference_id,
            'backend': self.backend,
            'seconds': float(self.seconds),
            'message': self.message,
        }
