"""Partial checkerboard grids in an image region (OpenCV ``findChessboardCornersSB``).

On MATRIX frames the boards are partly occluded by walking people and partly out of view, so the full
19 x 19 pattern is never found. ``findChessboardCornersSBWithMeta`` with a small pattern and the
LARGER | EXHAUSTIVE | ACCURACY flags finds the largest partial grid ("piece"); masking it and searching
again finds further pieces (the rest of an occluded board, the other board).

Speed and reliability: the search runs in a view of each board rectified with the prior pose
(:func:`matrix_core.calib.regions.board_rectification`, ~250 x 250 px, ~40-80 ms per call) instead of the
1920 x 1080 image (~1.5 s). In MATRIX images board rows are only 3-6 px apart; at reduced resolution (960 x
540 region search) most boards were lost, while the rectified view (squares ~10 px) finds 19 x 16 pieces.

Convention: corners are returned in full-resolution OpenCV pixel-centre coordinates (internal convention).
"""

from dataclasses import dataclass

import cv2
import numpy as np

SB_FLAGS = cv2.CALIB_CB_LARGER | cv2.CALIB_CB_EXHAUSTIVE


@dataclass
class GridPiece:
    """A detected partial grid: corner ``k`` has grid position ``grid_cr[k]`` = (column, row), ints, and
    pixel position ``uv[k]``. Grid neighbours are neighbouring inner corners of one board (which board,
    and which corners, is decided by :mod:`matrix_core.calib.assignment`)."""

    grid_cr: np.ndarray  # (N, 2) int
    uv: np.ndarray  # (N, 2) float pixels

    @property
    def count(self) -> int:
        return int(len(self.uv))


def clean_piece(grid: np.ndarray, threshold_px: float = 1.0, min_corners: int = 9):
    """Keep the corners of a (rows, cols, 2) grid that one plane homography explains (RANSAC).

    ``findChessboardCornersSB`` sometimes returns a grid with a few corners snapped to a person or to
    the board edge; a grid of board corners is exactly a homography image of its (column, row) indices,
    so those corners are outliers of that homography. Returns a :class:`GridPiece` or None.
    """
    rows, cols = grid.shape[:2]
    r, c = np.mgrid[0:rows, 0:cols]
    cr = np.stack([c.ravel(), r.ravel()], axis=1)
    uv = grid.reshape(-1, 2)
    if len(uv) < min_corners:
        return None
    _H, mask = cv2.findHomography(cr.astype(np.float64), uv, cv2.RANSAC, threshold_px, maxIters=500, confidence=0.999)
    if mask is None:
        return None
    keep = mask.ravel().astype(bool)
    if keep.sum() < min_corners:
        return None
    return GridPiece(cr[keep], uv[keep].copy())


def _mask_piece(image: np.ndarray, corners_px: np.ndarray) -> None:
    """Paint over a found piece (its hull grown by one grid step) with the image median, in place."""
    pts = corners_px.reshape(-1, 2)
    centre = pts.mean(axis=0)
    rows, cols = corners_px.shape[:2]
    steps = [np.linalg.norm(np.diff(corners_px, axis=a), axis=-1).mean() for a in (0, 1) if corners_px.shape[a] > 1]
    grow = 1.5 * max(steps) if steps else 4.0
    vec = pts - centre
    norm = np.linalg.norm(vec, axis=1, keepdims=True)
    grown = pts + vec / np.maximum(norm, 1e-9) * grow
    hull = cv2.convexHull(np.round(grown).astype(np.int32))
    cv2.fillConvexPoly(image, hull, int(np.median(image)))


def _refine(gray: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Sub-pixel refinement at full resolution, window half the smallest grid step (at least 2 px)."""
    grid = corners
    steps = [np.linalg.norm(np.diff(grid, axis=a), axis=-1).min() for a in (0, 1) if grid.shape[a] > 1]
    half = int(max(2, min(6, np.floor(min(steps) / 2.0)))) if steps else 3
    pts = grid.reshape(-1, 1, 2).astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 20, 0.01)
    refined = cv2.cornerSubPix(gray, pts, (half, half), (-1, -1), criteria)
    return refined.reshape(grid.shape).astype(np.float64)


def find_pieces(
    gray: np.ndarray,
    img_H_search=None,
    search_size=None,
    pattern_size: int = 3,
    max_pieces: int = 3,
    refine: bool = True,
    accuracy: bool = True,
) -> list:
    """Detect up to ``max_pieces`` partial grids in a search image warped out of ``gray``.

    Args:
        gray: (H, W) uint8 full-resolution image.
        img_H_search: (3, 3) homography search-image pixels -> ``gray`` pixels (a crop is a translation,
            a reduced scale a scaling, a board rectification a perspective map); None = ``gray`` itself.
        search_size: (width, height) of the search image (required with ``img_H_search``).
        pattern_size: n of the smallest n x n inner-corner grid accepted.
        max_pieces: stop after this many pieces.
        refine: refine the corners in ``gray`` at full resolution with ``cornerSubPix``.
        accuracy: ``findChessboardCornersSB`` with ``CALIB_CB_ACCURACY`` (about 40 % slower, fewer outliers).

    Returns:
        list of :class:`GridPiece` in ``gray`` pixels, in the order found (largest first).
    """
    if img_H_search is None:
        search = gray.copy()
    else:
        search = cv2.warpPerspective(
            gray,
            np.asarray(img_H_search, dtype=np.float64),
            tuple(search_size),
            flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=int(np.median(gray)),
        )
    pieces = []
    for _ in range(max_pieces):
        found, corners, meta = cv2.findChessboardCornersSBWithMeta(
            search, (pattern_size, pattern_size), SB_FLAGS | (cv2.CALIB_CB_ACCURACY if accuracy else 0)
        )
        if not found or corners is None or meta is None:
            break
        rows, cols = meta.shape[:2]
        if rows * cols != len(corners):
            break
        grid = corners.reshape(rows, cols, 2).astype(np.float64)
        _mask_piece(search, grid)
        if img_H_search is not None:
            grid = cv2.perspectiveTransform(grid.reshape(-1, 1, 2), np.asarray(img_H_search, dtype=np.float64))
            grid = grid.reshape(rows, cols, 2)
        # Corners mapped back from a rectified view can fall outside the image: drop such pieces.
        if not (np.all(np.isfinite(grid)) and np.all((grid >= 2) & (grid <= np.array(gray.shape[1::-1]) - 3))):
            continue
        if refine and img_H_search is not None:
            grid = _refine(gray, grid)
        piece = clean_piece(grid)
        if piece is not None:
            pieces.append(piece)
    return pieces
