"""How the ground moved in the image since the previous frame: an ORB + RANSAC plane homography.

Between two frames 0.5 s apart a MATRIX drone turns by 4.4 deg (median, up to 14 deg) and moves about
0.3 m: the boards move by 100-300 px in the image and their perspective changes. Composing the previous
pose's ground projection with this homography predicts every board corner to a fraction of a square in
most frames (measured on the real sample), which both places the search windows and nearly names the
corners. People and the central block are RANSAC outliers; the ground dominates the view.

When the homography fails, a phase correlation of two small grey images gives at least the global
translation (:mod:`matrix_core.calib.regions`). :class:`PriorImageMotion` measures either from the image the
prior pose belongs to.

Convention: ``cur_H_prev`` maps full-resolution pixels (pixel-centre convention) of the previous image
to the current image.
"""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.calib.regions import image_shift, small_gray, translation
from matrix_core.calib.settings import CalibSettings


# LSH: about 35 ms instead of 100-150 ms for 3000 x 3000 binary descriptors, slightly worse priors
# (its hash tables draw from OpenCV's RNG, which the calibrator seeds per image).
MATCHERS = {
    'lsh': lambda: cv2.FlannBasedMatcher(
        dict(algorithm=6, table_number=6, key_size=12, multi_probe_level=1), dict(checks=50)
    ),
    'brute': lambda: cv2.BFMatcher(cv2.NORM_HAMMING),
}


@dataclass
class Features:
    """ORB keypoints (K, 2) full-resolution pixels and (K, 32) uint8 descriptors of one image."""

    points: np.ndarray
    descriptors: np.ndarray


class GroundMotion:
    """ORB features at ``scale`` of the full image and the homography between two frames' features."""

    def __init__(
        self,
        scale: float = 0.5,
        features: int = 3000,
        ratio: float = 0.8,
        ransac_px: float = 2.0,
        min_inliers: int = 40,
        matcher: str = 'brute',
    ):
        self.scale, self.ratio, self.ransac_px, self.min_inliers = scale, ratio, ransac_px, min_inliers
        self.orb = cv2.ORB_create(features, fastThreshold=10)
        if matcher not in MATCHERS:
            raise ValueError(f'matcher must be one of {sorted(MATCHERS)}, got {matcher!r}')
        self.matcher, self.matchers = matcher, {}

    def features(self, gray: np.ndarray) -> Features:
        """ORB features of an (H, W) uint8 image (found at ``scale``, returned in full-resolution pixels)."""
        small = cv2.resize(gray, None, fx=self.scale, fy=self.scale, interpolation=cv2.INTER_AREA)
        kps, desc = self.orb.detectAndCompute(small, None)
        pts = np.array([k.pt for k in kps], dtype=np.float64).reshape(-1, 2)
        pts = (pts + 0.5) / self.scale - 0.5
        return Features(pts, desc if desc is not None else np.zeros((0, 32), np.uint8))

    def homography(self, previous: Features, current: Features, matcher: str = ''):
        """(cur_H_prev (3, 3), inlier count) or (None, inliers) when too few matches agree; ``matcher``
        ('lsh' or 'brute') overrides the one given at construction."""
        if previous is None or len(previous.points) < 8 or len(current.points) < 8:
            return None, 0
        name = matcher or self.matcher
        if name not in MATCHERS:
            raise ValueError(f'matcher must be one of {sorted(MATCHERS)}, got {name!r}')
        if name not in self.matchers:  # made on first use: most calibrators only ever use one
            self.matchers[name] = MATCHERS[name]()
        pairs = self.matchers[name].knnMatch(previous.descriptors, current.descriptors, k=2)
        good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < self.ratio * p[1].distance]
        if len(good) < self.min_inliers:
            return None, len(good)
        src = previous.points[[m.queryIdx for m in good]]
        dst = current.points[[m.trainIdx for m in good]]
        H, mask = cv2.findHomography(src, dst, cv2.RANSAC, self.ransac_px / self.scale, maxIters=2000, confidence=0.999)
        inliers = int(mask.sum()) if mask is not None else 0
        if H is None or inliers < self.min_inliers or not np.all(np.isfinite(H)):
            return None, inliers
        return H / H[2, 2], inliers


class PriorImageMotion:
    """The image motion from the image the prior pose belongs to (the last good frame, or the reference
    image) to the current one: the ORB ground homography, else the phase-correlation shift.

    Args:
        settings: ``motion_*`` and ``global_shift_scale`` (0 = that measure off).
        prior_gray: (H, W) uint8 image of the first prior (the reference image), optional.
    """

    def __init__(self, settings: CalibSettings, prior_gray: np.ndarray = None):
        self.settings = settings
        self.ground = (
            GroundMotion(settings.motion_scale, settings.motion_features, matcher=settings.motion_matcher)
            if settings.motion_scale > 0
            else None
        )
        self.prior_features = self.prior_small = None
        self.prior_gray = prior_gray

    def measure(self, gray: np.ndarray) -> tuple:
        """(ORB features or None, small grey image or None) of an (H, W) uint8 image: its motion data."""
        s = self.settings
        features = self.ground.features(gray) if self.ground is not None else None
        small = small_gray(gray, s.global_shift_scale) if s.global_shift_scale > 0 else None
        return features, small

    def remember(self, gray: np.ndarray, motion_data: tuple = None) -> None:
        """Make ``gray`` the prior's image; its ``motion_data`` is measured only if a later frame needs it."""
        if motion_data is None:
            self.prior_gray, self.prior_features, self.prior_small = gray, None, None
        else:
            self.prior_gray, (self.prior_features, self.prior_small) = None, motion_data

    def _measure_prior(self) -> None:
        """Measure the prior's image now that a frame needs it (kept as a grey image till then: frames guided
        by a registration never need it)."""
        if self.prior_gray is not None:
            self.prior_features, self.prior_small = self.measure(self.prior_gray)
            self.prior_gray = None

    def since_prior(self, motion_data: tuple, matcher: str = '') -> tuple:
        """(cur_H_prev (3, 3) or None, how it was measured, whether it is a full ground homography) from the
        current image's ``motion_data`` (ORB ``matcher``, '' = ``motion_matcher``)."""
        self._measure_prior()
        features, small = motion_data
        H, how = None, 'none'
        if features is not None and self.prior_features is not None:
            H, inliers = self.ground.homography(self.prior_features, features, matcher)
            how = f'homography ({inliers} inliers)' if H is not None else f'homography failed ({inliers})'
        homography = H is not None
        if H is None and small is not None and self.prior_small is not None:
            H = translation(image_shift(self.prior_small, small, self.settings.global_shift_scale))
            how = 'shift' if how == 'none' else f'{how}; shift'
        return H, how, homography
