"""How the ground moved in the image since the previous frame: an ORB + RANSAC plane homography.

Between two frames 0.5 s apart a MATRIX drone turns by 4.4 deg (median, up to 14 deg) and moves about
0.3 m: the boards move by 100-300 px in the image and their perspective changes. Composing the previous
pose's ground projection with this homography predicts every board corner to a fraction of a square in
most frames (measured on the real sample), which both places the search windows and nearly names the
corners. People and the central block are RANSAC outliers; the ground dominates the view.

Convention: ``cur_H_prev`` maps full-resolution pixels (pixel-centre convention) of the previous image
to the current image.
"""

from dataclasses import dataclass

import cv2
import numpy as np


# LSH: about 35 ms instead of 100-150 ms for 3000 x 3000 binary descriptors, slightly worse priors
# (its hash tables draw from OpenCV's RNG, which the tracker seeds per image).
MATCHERS = {'lsh': lambda: cv2.FlannBasedMatcher(dict(algorithm=6, table_number=6, key_size=12, multi_probe_level=1),
                                                 dict(checks=50)),
            'brute': lambda: cv2.BFMatcher(cv2.NORM_HAMMING)}


@dataclass
class Features:
    """ORB keypoints (K, 2) full-resolution pixels and (K, 32) uint8 descriptors of one image."""

    points: np.ndarray
    descriptors: np.ndarray


class GroundMotion:
    """ORB features at ``scale`` of the full image and the homography between two frames' features."""

    def __init__(self, scale: float = 0.5, features: int = 3000, ratio: float = 0.8,
                 ransac_px: float = 2.0, min_inliers: int = 40, matcher: str = 'brute'):
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
        if name not in self.matchers:   # made on first use: most trackers only ever use one
            self.matchers[name] = MATCHERS[name]()
        pairs = self.matchers[name].knnMatch(previous.descriptors, current.descriptors, k=2)
        good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < self.ratio * p[1].distance]
        if len(good) < self.min_inliers:
            return None, len(good)
        src = previous.points[[m.queryIdx for m in good]]
        dst = current.points[[m.trainIdx for m in good]]
        H, mask = cv2.findHomography(src, dst, cv2.RANSAC, self.ransac_px / self.scale, maxIters=2000,
                                     confidence=0.999)
        inliers = int(mask.sum()) if mask is not None else 0
        if H is None or inliers < self.min_inliers or not np.all(np.isfinite(H)):
            return None, inliers
        return H / H[2, 2], inliers
