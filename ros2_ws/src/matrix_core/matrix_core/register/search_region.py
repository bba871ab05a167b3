"""Where a frame's features can match the reference's: the reference's ground, carried into the current image
by a predicted registration.

The reference keeps only its ground features (:class:`~matrix_core.register.reference.Reference`), so a feature
of the current image can match one only where it shows that ground. When a registration predicts where the
current frame lies (mode track: the doubted chain's own estimate), the reference's ground mask warped into the
current image by it, grown by the prediction's possible error, is all the feature backend needs to describe:
on the real MATRIX sample the ground is a third to a half of each image and its bounding box about half the
rows, so SIFT builds its pyramid on the crop and describes the masked features only.
"""

import cv2
import numpy as np

from matrix_core.geometry.homography import pixel_scale_homography


def predicted_region(reference_mask: np.ndarray, ref_H_cur: np.ndarray, scale: float, margin_px: float) -> np.ndarray:
    """(h, w) bool mask of the current image at ``scale`` (the reference mask's size): the reference's ground
    ``reference_mask`` (h, w) bool (at the same scale, :func:`~matrix_core.register.ground_mask.ground_mask`)
    seen through the predicted ``ref_H_cur`` (3, 3; current -> reference full-resolution pixels), grown by
    ``margin_px`` full-resolution pixels."""
    full_H_small = pixel_scale_homography(1 / scale, 1 / scale)
    ref_small_H_cur_small = np.linalg.inv(full_H_small) @ ref_H_cur @ full_H_small
    h, w = reference_mask.shape
    # WARP_INVERSE_MAP: each current pixel looks up where the prediction puts it in the reference mask
    warped = cv2.warpPerspective(
        reference_mask.astype(np.uint8),
        ref_small_H_cur_small,
        (w, h),
        flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP,
        borderValue=0,
    )
    grow = int(np.ceil(margin_px * scale))
    if grow > 0:
        warped = cv2.dilate(warped, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * grow + 1, 2 * grow + 1)))
    return warped.astype(bool)
