"""Ground truth and error of a registration, from the stored calibrations (acceptance metric)."""

import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.geometry.homography import apply_homography
from matrix_core.register.ground_mask import visible_ground_grid


def gt_cur_to_ref(cur: Camera, ref: Camera) -> np.ndarray:
    """(3, 3) true ``ref_H_img`` of the ground plane: img_ref <- ground <- img_cur."""
    H = ref.img_H_ground() @ cur.ground_H_img()
    return H / H[2, 2]


def homography_error_px(ref_H_img: np.ndarray, cur: Camera, ref: Camera, area, boxes=(), step_m: float = 0.5) -> float:
    """Mean distance in full-resolution reference pixels between ``ref_H_img`` and the ground truth,
    over a ``step_m`` grid of ground points of ``area`` visible (ground, not behind ``boxes``) in ``cur``.
    """
    world = visible_ground_grid(cur, area, step_m, boxes)
    if not len(world):
        raise ValueError('no ground point of the area is visible in the current image')
    uv_cur = cur.ground_to_img(world)
    est = apply_homography(ref_H_img, uv_cur)
    truth = ref.ground_to_img(world)
    return float(np.mean(np.linalg.norm(est - truth, axis=1)))
