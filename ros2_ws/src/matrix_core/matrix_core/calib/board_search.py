"""The checkerboard search of one frame, where a prior pose predicts the boards.

Each board is searched in a view rectified with its prediction (``regions``, ``detection``), or, when none
is found anywhere, in the whole image at ``full_search_scale``; the pieces' corners are named
(``assignment``), RANSAC/LM PnP gives a pose (``pnp``) and every board corner is refined, verified and the
position corrected by whole squares (``grow``). The calibrator then checks the pose's plausibility.
"""

import time
from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.calib.assignment import assign_piece
from matrix_core.calib.detection import find_pieces
from matrix_core.calib.grow import grow_pose
from matrix_core.calib.pnp import PnPResult, solve_pnp
from matrix_core.calib.regions import board_rectification
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.geometry.camera import Camera
from matrix_core.geometry.homography import pixel_scale_homography


@dataclass
class BoardSearch:
    """Outcome of :func:`search_boards`: ``fit`` None when no pose was found (``message`` says why)."""

    fit: PnPResult = None
    correction: tuple = (0, 0)  # whole squares the grid was corrected by
    message: str = ''
    corners: int = 0  # corners assigned (or PnP inliers when the pose was ambiguous)
    pieces_found: int = 0
    pieces_assigned: int = 0
    full_search: bool = False


def find_board_pieces(
    gray: np.ndarray, scene: CalibScene, settings: CalibSettings, predicted: dict, prior: Camera, rough: bool
) -> tuple:
    """(pieces (list of GridPiece), whether the whole image was searched): pieces near the boards
    ``predicted`` puts in the (H, W) grey image, else (``full_search``) anywhere in it."""
    s = settings
    margin = s.initial_margin_cells if rough else s.margin_cells
    pieces = []
    for board in scene.boards:
        rect = board_rectification(predicted[board.name], board, prior, s.px_per_square, margin)
        if rect is not None:
            pieces += find_pieces(
                gray, rect[0], rect[1], s.pattern_size, s.max_pieces_per_board, s.refine_subpixel, s.detect_accuracy
            )
    full_search = not pieces and s.full_search
    if full_search:
        scale, (width, height) = s.full_search_scale, scene.image_size
        img_H_search = None if scale == 1 else pixel_scale_homography(1.0 / scale, 1.0 / scale)
        pieces = find_pieces(
            gray,
            img_H_search,
            (round(width * scale), round(height * scale)),
            s.pattern_size,
            s.max_pieces_per_board * len(scene.boards),
            refine=False,
            accuracy=s.detect_accuracy,
        )
    return pieces, full_search


def assign_pieces(
    gray: np.ndarray,
    pieces: list,
    scene: CalibScene,
    settings: CalibSettings,
    predicted: dict,
    prior: Camera,
    rough: bool,
    max_turn_deg: float,
) -> tuple:
    """((N, 3) world, (N, 2) pixels, reasons the rejected pieces were rejected, pieces assigned): every
    piece's corners named; a corner found twice counts once."""
    s = settings
    smooth = cv2.GaussianBlur(gray, (3, 3), 0).astype(np.float32)
    world, uv, reasons, assigned = [], [], [], 0
    used = set()
    predicted_ij = {name: np.linalg.inv(H) for name, H in predicted.items()}
    max_index_error = s.max_index_error * (4.0 if rough else 1.0)
    for piece in pieces:
        a, why = assign_piece(
            piece,
            scene.boards,
            predicted_ij,
            prior,
            smooth,
            max_index_error,
            s.ambiguity_ratio,
            s.index_separation,
            max(max_turn_deg, s.max_prior_rotation_deg),
            2.0 * s.max_reprojection_px,
        )
        if a is None:
            reasons.append(why)
            continue
        assigned += 1
        for (i, j), p, w in zip(a.indices, a.image_uv, a.world):
            if (a.board.name, i, j) not in used:
                used.add((a.board.name, i, j))
                world.append(w)
                uv.append(p)
    return world, uv, reasons, assigned


def search_boards(
    gray: np.ndarray,
    scene: CalibScene,
    settings: CalibSettings,
    predicted: dict,
    prior: Camera,
    rough: bool,
    max_turn_deg: float,
    timings: dict,
) -> BoardSearch:
    """The pose of the (H, W) grey image from checkerboard pieces searched where ``predicted`` (board name ->
    (3, 3) image pixels <- corner indices) puts the boards.

    ``prior`` is the pose they were predicted from, ``rough`` True when that prediction can be metres off
    (wider search and naming margins), ``max_turn_deg`` the rotation from the prior still plausible.
    Stage times (s) are added to ``timings`` ('detect', 'assign', 'pnp')."""
    s = settings
    t = time.perf_counter()
    pieces, full_search = find_board_pieces(gray, scene, s, predicted, prior, rough)
    timings['detect'] = time.perf_counter() - t
    t = time.perf_counter()
    world, uv, reasons, assigned = assign_pieces(gray, pieces, scene, s, predicted, prior, rough, max_turn_deg)
    timings['assign'] = time.perf_counter() - t
    outcome = BoardSearch(
        corners=len(world), pieces_found=len(pieces), pieces_assigned=assigned, full_search=full_search
    )
    t = time.perf_counter()
    if len(world) < s.min_corners:
        why = '; '.join(sorted(set(reasons))) or 'no board piece found'
        outcome.message = f'{len(world)} corners assigned (< {s.min_corners}): {why}'
        return outcome
    fit = solve_pnp(np.array(world), np.array(uv), scene.camera(np.eye(4)), s.pnp_ransac_px)
    timings['pnp'] = time.perf_counter() - t
    if fit is None:
        outcome.message = 'PnP failed'
        return outcome
    if s.grow_corners and fit.inliers.sum() >= s.min_corners:
        grown, correction = grow_pose(gray, fit.camera, scene, s)
        if correction is None:
            outcome.corners = int(fit.inliers.sum())
            outcome.message = 'ambiguous board position: the board edges that would decide it are out of view'
            return outcome
        if grown is not None:
            outcome.fit, outcome.correction = grown, correction
            return outcome
    outcome.fit = fit
    return outcome
