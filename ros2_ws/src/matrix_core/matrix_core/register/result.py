"""What one registration returns (per drone and frame)."""

from dataclasses import dataclass

import numpy as np

STATUS_OK = 'ok'
STATUS_FAILED = 'failed'


@dataclass(frozen=True)
class RegistrationResult:
    """Registration of one current image to its drone's reference image.

    Convention:
        ``H_cur_to_ref`` (3, 3) maps current-image pixels to reference-image pixels (full resolution,
        internal pixel-centre convention), normalised to H[2, 2] = 1. ``H_img_to_ground`` (3, 3) maps
        current-image pixels to internal world ground metres (z = 0):
        ``H_img_to_ground = ref.ground_H_img() @ H_cur_to_ref``. Both are None unless status is 'ok'.

    Attributes:
        status: 'ok' or 'failed' (too few inliers, NaN/degenerate H, or rejected by the sanity gate).
        confidence: inliers / matches (0 without matches).
        matches: symmetric ratio-test matches; inliers: robust-fit inliers among them.
        inlier_error_px: mean inlier reprojection error in full-resolution reference pixels (NaN if none).
        reference_id: the reference the homography is chained through (e.g. 'D1/reference' or
            'D1/reference<-key:17' after re-keying).
        backend: feature backend name; seconds: wall time of the registration.
        message: why it failed, or what happened (re-keying, retrying the reference); '' otherwise.
        implied_center: (3,) world metres of the camera centre the ground homography implies (gate), or None.
    """

    status: str
    H_cur_to_ref: np.ndarray
    H_img_to_ground: np.ndarray
    confidence: float
    matches: int
    inliers: int
    inlier_error_px: float
    reference_id: str
    backend: str
    seconds: float
    message: str = ''
    implied_center: np.ndarray = None

    @property
    def ok(self) -> bool:
        return self.status == STATUS_OK

    def to_dict(self) -> dict:
        """JSON-ready dict (matrices as nested lists, or None)."""
        def mat(H):
            return None if H is None else np.asarray(H, dtype=float).tolist()

        def num(v):
            return None if v is None or not np.isfinite(v) else float(v)

        return {'status': self.status, 'H_cur_to_ref': mat(self.H_cur_to_ref),
                'H_img_to_ground': mat(self.H_img_to_ground), 'confidence': float(self.confidence),
                'matches': int(self.matches), 'inliers': int(self.inliers),
                'inlier_error_px': num(self.inlier_error_px), 'reference_id': self.reference_id,
                'backend': self.backend, 'seconds': float(self.seconds), 'message': self.message}
