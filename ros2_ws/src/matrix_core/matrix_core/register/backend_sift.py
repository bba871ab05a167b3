"""OpenCV SIFT backend: the fast CPU default (no weights)."""

import cv2
import numpy as np

from matrix_core.register.features import Features, mask_at, resize, to_full_resolution, to_gray

# Rows and columns of context kept around a mask's bounding box when SIFT runs on the crop (working-size
# pixels): a feature's blurs and descriptor window reach a few times its scale beyond it, and features at the
# mask's edge are small ones (large ones on the plaza are rare).
CROP_BORDER = 16


def _no_features() -> Features:
    return Features(np.zeros((0, 2)), np.zeros((0, 128), np.float32))


class SiftBackend:
    """OpenCV SIFT on an image resized by ``scale``; RootSIFT-free plain descriptors (L2 matching).

    ``contrast_threshold`` matters here: the plaza is low-texture concrete, and OpenCV's default 0.04 puts
    almost every feature on the buildings (whose homography is not the ground's).
    """

    name = 'sift'

    def __init__(self, scale: float = 0.5, contrast_threshold: float = 0.01):
        self.scale = scale
        self.contrast_threshold = contrast_threshold

    def extract(self, image: np.ndarray, max_features: int, mask: np.ndarray = None) -> Features:
        gray = resize(to_gray(image), self.scale)
        sift = cv2.SIFT_create(nfeatures=int(max_features), contrastThreshold=self.contrast_threshold)
        x0 = y0 = 0
        if mask is not None:  # SIFT on the mask's bounding box (plus context), features inside the mask
            mask = mask_at(mask, gray.shape)
            rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
            if not len(rows):
                return _no_features()
            y0, y1 = max(rows[0] - CROP_BORDER, 0), min(rows[-1] + 1 + CROP_BORDER, gray.shape[0])
            x0, x1 = max(cols[0] - CROP_BORDER, 0), min(cols[-1] + 1 + CROP_BORDER, gray.shape[1])
            gray, mask = gray[y0:y1, x0:x1], mask[y0:y1, x0:x1].astype(np.uint8)
        kps, desc = sift.detectAndCompute(gray, mask)
        if desc is None or not kps:
            return _no_features()
        xy = np.array([k.pt for k in kps], dtype=np.float64) + (x0, y0)
        # OpenCV keypoints are pixel-centre coordinates of the resized image.
        return Features(to_full_resolution(xy, self.scale), desc.astype(np.float32))
