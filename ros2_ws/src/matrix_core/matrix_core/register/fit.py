"""Robust homography fit (RANSAC or MAGSAC) with the numbers a caller needs to judge it."""

from dataclasses import dataclass

import cv2
import numpy as np

_METHODS = {'ransac': cv2.RANSAC, 'magsac': cv2.USAC_MAGSAC}


@dataclass(frozen=True)
class HomographyFit:
    """Result of :func:`fit_homography`.

    Attributes:
        H: (3, 3) ``dst_H_src`` normalised to H[2, 2] = 1, or None when no valid homography was found.
        inliers: (M,) bool inlier mask over the input correspondences.
        error_px: mean reprojection error of the inliers in destination pixels (NaN without inliers).
        reason: why H is None ('' when valid).
    """

    H: np.ndarray
    inliers: np.ndarray
    error_px: float
    reason: str = ''


def is_valid_homography(H) -> str:
    """'' if ``H`` is a usable (3, 3) homography, else the reason (NaN, near-singular, degenerate)."""
    if H is None:
        return 'no homography'
    H = np.asarray(H, dtype=np.float64)
    if H.shape != (3, 3) or not np.all(np.isfinite(H)):
        return 'homography has NaN/inf entries'
    if abs(H[2, 2]) < 1e-12:
        return 'homography has H[2,2] = 0'
    Hn = H / H[2, 2]
    s = np.linalg.svd(Hn, compute_uv=False)
    if s[-1] <= 1e-9 * s[0]:
        return 'homography is singular (degenerate correspondences)'
    return ''


def fit_homography(src: np.ndarray, dst: np.ndarray, method: str = 'magsac', threshold_px: float = 3.0,
                   max_iters: int = 5000, confidence: float = 0.999) -> HomographyFit:
    """Fit ``dst_H_src`` to (M, 2) correspondences ``src[k] -> dst[k]`` robustly.

    ``threshold_px`` is the inlier distance in ``dst`` pixels. Fewer than 4 points, a NaN/singular result
    or an estimator failure give ``H = None`` with the reason.
    """
    src = np.asarray(src, dtype=np.float64).reshape(-1, 2)
    dst = np.asarray(dst, dtype=np.float64).reshape(-1, 2)
    none = np.zeros(len(src), dtype=bool)
    if len(src) < 4:
        return HomographyFit(None, none, float('nan'), f'only {len(src)} matches (need 4)')
    if not (np.all(np.isfinite(src)) and np.all(np.isfinite(dst))):
        return HomographyFit(None, none, float('nan'), 'NaN keypoint coordinates')
    H, mask = cv2.findHomography(src, dst, _METHODS[method], threshold_px, maxIters=max_iters,
                                 confidence=confidence)
    reason = is_valid_homography(H)
    if reason:
        return HomographyFit(None, none, float('nan'), reason)
    H = H / H[2, 2]
    inliers = mask.reshape(-1).astype(bool)
    proj = cv2.perspectiveTransform(src[inliers].reshape(-1, 1, 2), H).reshape(-1, 2)
    err = float(np.mean(np.linalg.norm(proj - dst[inliers], axis=1))) if inliers.any() else float('nan')
    return HomographyFit(H, inliers, err)
