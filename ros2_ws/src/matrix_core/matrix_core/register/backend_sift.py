"""OpenCV SIFT backend: the fast CPU default (no weights)."""

import cv2
import numpy as np

from matrix_core.register.features import Features, resize, to_full_resolution, to_gray


class SiftBackend:
    """OpenCV SIFT on an image resized by ``scale``; RootSIFT-free plain descriptors (L2 matching).

    ``contrast_threshold`` matters here: the plaza is low-texture concrete, and OpenCV's default 0.04 puts
    almost every feature on the buildings (whose homography is not the ground's).
    """

    name = 'sift'

    def __init__(self, scale: float = 0.5, contrast_threshold: float = 0.01):
        self.scale = scale
        self.contrast_threshold = contrast_threshold

    def extract(self, image: np.ndarray, max_features: int) -> Features:
        gray = resize(to_gray(image), self.scale)
        sift = cv2.SIFT_create(nfeatures=int(max_features), contrastThreshold=self.contrast_threshold)
        kps, desc = sift.detectAndCompute(gray, None)
        if desc is None or not kps:
            return Features(np.zeros((0, 2)), np.zeros((0, 128), np.float32))
        xy = np.array([k.pt for k in kps], dtype=np.float64)
        # OpenCV keypoints are pixel-centre coordinates of the resized image.
        return Features(to_full_resolution(xy, self.scale), desc.astype(np.float32))
