"""Robust homography fit (RANSAC or MAGSAC) with the numbers a caller needs to judge it.

``magsac`` is OpenCV's USAC_MAGSAC flag: deterministic (its sampler does not read any seed; the same
correspondences always give the same H). ``ransac`` is the paper's plain RANSAC (uniform minimal samples,
inlier-count score, no local optimisation, least-squares refit on the inliers) through OpenCV's USAC with
its random generator state set to ``seed``: the same seed repeats, other seeds draw other samples, which
is what the paper's run-to-run variation (10 runs varying the registration's RANSAC) measures. OpenCV's
classic ``cv2.RANSAC`` flag is not used: it reseeds a fixed generator on every call (``cv2.setRNGSeed``
does not reach it), so it cannot vary.
"""

from dataclasses import dataclass

import cv2
import numpy as np

METHODS = ('ransac', 'magsac')


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


def plain_ransac_params(threshold_px: float, max_iters: int, confidence: float, seed: int) -> 'cv2.UsacParams':
    """OpenCV USAC parameters of plain, seeded RANSAC (see the module docstring)."""
    p = cv2.UsacParams()
    p.threshold, p.confidence, p.maxIterations = float(threshold_px), float(confidence), int(max_iters)
    p.sampler, p.score = cv2.SAMPLING_UNIFORM, cv2.SCORE_METHOD_RANSAC
    p.loMethod, p.final_polisher = cv2.LOCAL_OPTIM_NULL, cv2.LSQ_POLISHER
    p.randomGeneratorState = int(seed) % 2**32  # an unsigned 32-bit state
    p.isParallel = False  # parallel USAC would not repeat
    return p


def fit_homography(
    src: np.ndarray,
    dst: np.ndarray,
    method: str = 'magsac',
    threshold_px: float = 3.0,
    max_iters: int = 5000,
    confidence: float = 0.999,
    seed: int = 0,
) -> HomographyFit:
    """Fit ``dst_H_src`` to (M, 2) correspondences ``src[k] -> dst[k]`` robustly.

    ``threshold_px`` is the inlier distance in ``dst`` pixels; ``seed`` the random state of ``ransac``
    (``magsac`` is deterministic and ignores it). Fewer than 4 points, a NaN/singular result or an
    estimator failure give ``H = None`` with the reason.
    """
    if method not in METHODS:
        raise ValueError(f'unknown robust estimator {method!r}; choose one of {METHODS}')
    src = np.asarray(src, dtype=np.float64).reshape(-1, 2)
    dst = np.asarray(dst, dtype=np.float64).reshape(-1, 2)
    none = np.zeros(len(src), dtype=bool)
    if len(src) < 4:
        return HomographyFit(None, none, float('nan'), f'only {len(src)} matches (need 4)')
    if not (np.all(np.isfinite(src)) and np.all(np.isfinite(dst))):
        return HomographyFit(None, none, float('nan'), 'NaN keypoint coordinates')
    try:
        if method == 'ransac':
            H, mask = cv2.findHomography(src, dst, plain_ransac_params(threshold_px, max_iters, confidence, seed))
        else:
            H, mask = cv2.findHomography(
                src, dst, cv2.USAC_MAGSAC, threshold_px, maxIters=max_iters, confidence=confidence
            )
    except cv2.error as exc:  # USAC raises on degenerate input where the flag API returns None
        return HomographyFit(None, none, float('nan'), f'estimator failed: {str(exc).strip().splitlines()[-1]}')
    reason = is_valid_homography(H)
    if reason:
        return HomographyFit(None, none, float('nan'), reason)
    H = H / H[2, 2]
    inliers = mask.reshape(-1).astype(bool)
    proj = cv2.perspectiveTransform(src[inliers].reshape(-1, 1, 2), H).reshape(-1, 2)
    err = float(np.mean(np.linalg.norm(proj - dst[inliers], axis=1))) if inliers.any() else float('nan')
    return HomographyFit(H, inliers, err)
