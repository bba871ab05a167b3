"""Pictures of a registration: the current image warped onto the reference, checkerboarded with it, under
the reference's ground grid, so the quality can be judged by eye (edges continue across tile borders and
the grid sits on the same ground marks in both kinds of tiles when the homography is right)."""

from pathlib import Path

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.output_paths import atomic_path


def _scaling(s: float) -> np.ndarray:
    """(3, 3) full-resolution pixel-centre coordinates -> coordinates of an image resized by ``s``."""
    return np.array([[s, 0, 0.5 * s - 0.5], [0, s, 0.5 * s - 0.5], [0, 0, 1.0]])


def _grid_lines(camera: Camera, area, step_m: float, samples: int = 60) -> list:
    """Polylines (each (K, 2) reference pixels) of a ``step_m`` grid over ``area``, parts in front of the camera."""
    x0, y0, x1, y1 = area
    lines = [np.c_[np.full(samples, x), np.linspace(y0, y1, samples)] for x in np.arange(x0, x1 + 1e-9, step_m)]
    lines += [np.c_[np.linspace(x0, x1, samples), np.full(samples, y)] for y in np.arange(y0, y1 + 1e-9, step_m)]
    out = []
    for xy in lines:
        front = camera.depth(np.c_[xy, np.zeros(len(xy))]) > 0
        uv = camera.ground_to_img(xy)
        keep = front & np.all(np.isfinite(uv), axis=1) & (np.abs(uv) < 1e5).all(axis=1)
        # Split where points drop out, so that no segment jumps across the horizon.
        for run in np.split(np.arange(len(xy)), np.flatnonzero(np.diff(keep.astype(int)) != 0) + 1):
            if keep[run[0]] and len(run) >= 2:
                out.append(uv[run])
    return out


def registration_overlay(
    current: np.ndarray,
    reference: np.ndarray,
    ref_H_img,
    ref_camera: Camera,
    area,
    title: str = '',
    scale: float = 0.5,
    tile_px: int = 64,
    grid_m: float = 1.0,
) -> np.ndarray:
    """(h, w, 3) BGR picture at ``scale`` of the reference image size.

    Args:
        current, reference: (H, W, 3) BGR images at full resolution.
        ref_H_img: (3, 3) current-image pixels -> reference-image pixels, or None (failed: only the
            reference and the title are drawn).
        ref_camera: reference calibration (its ground grid over ``area``, internal world metres, is drawn).
        tile_px: checkerboard tile size in output pixels: tiles alternate reference / warped current.
    """
    S = _scaling(scale)
    h, w = round(reference.shape[0] * scale), round(reference.shape[1] * scale)
    ref_small = cv2.resize(reference, (w, h), interpolation=cv2.INTER_AREA)
    picture = (ref_small * 0.5).astype(np.uint8)
    if ref_H_img is not None:
        warped = cv2.warpPerspective(current, S @ np.asarray(ref_H_img, float), (w, h), flags=cv2.INTER_LINEAR)
        covered = (
            cv2.warpPerspective(
                np.full(current.shape[:2], 255, np.uint8),
                S @ np.asarray(ref_H_img, float),
                (w, h),
                flags=cv2.INTER_NEAREST,
            )
            > 0
        )
        rows, cols = np.indices((h, w))
        odd = ((rows // tile_px + cols // tile_px) % 2).astype(bool)
        picture = np.where((covered & odd)[..., None], warped, ref_small)
        picture[~covered] = (ref_small[~covered] * 0.5).astype(np.uint8)
    for uv in _grid_lines(ref_camera, area, grid_m):
        pts = cv2.perspectiveTransform(uv.reshape(-1, 1, 2), S).reshape(-1, 2)
        cv2.polylines(picture, [np.round(pts * 4).astype(np.int32)], False, (0, 255, 0), 1, cv2.LINE_AA, shift=2)
    if title:
        cv2.rectangle(picture, (0, 0), (w, 24), (0, 0, 0), -1)
        cv2.putText(picture, title, (6, 17), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return picture


def write_registration_overlay(path, *args, **kwargs) -> Path:
    """:func:`registration_overlay` written as a PNG to ``path`` (folders created); returns the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), registration_overlay(*args, **kwargs)):
            raise OSError(f'cannot write {path}')
    return path
