"""Grow a pose's support to every visible board corner, and correct it by whole squares if needed.

The detected pieces often cover only part of a board (people, the image border and the search itself stop
them); a pose from 40-60 corners in one part of the image can be 0.3-0.8 deg off, and a piece assigned
one square diagonally off (the colours agree) gives a pose 0.35 m off. Once a pose is known to a fraction
of a square, every board corner AND the virtual corners a few squares beyond the board are predicted.
Each is refined with ``cornerSubPix`` in a view rectified with that pose (squares ``px_per_square`` wide,
so the window sees a normal checker corner, unlike the 3-6 px high rows of the raw image) and verified:
it barely moved and the four squares around it form a dark/light saddle of strong contrast.

The verified saddles then decide the whole-square correction ``d``: the true board must cover as many
verified saddles of the right colour as possible, and ground beyond its edges has none. The corrected
correspondences (true index = predicted index + ``d``) are returned for the final PnP; :func:`grow_pose`
does all of it, solving the pose again from the verified corners until it settles.
"""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.calib.board import Checkerboard
from matrix_core.calib.pnp import solve_pnp
from matrix_core.calib.regions import image_H_board
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.geometry.camera import Camera, rotation_angle_deg

GROW_SHIFT = 4  # largest whole-square correction considered (the initial prior can be squares off)
# Tracking (corner_tracking) starts from a prediction a fraction of a square off, so at a pose solved from
# its corrected saddles it checks slips of up to TRACK_VERIFY_SHIFT squares only: 25 x 25 instead of 29 x 29
# corners refined per 19 x 19 board (the virtual corners beyond the board are ground, where cornerSubPix runs
# all its iterations; measured: calib 49 -> 39 ms per frame on simulated complex). A search from a prior squares
# off keeps GROW_SHIFT: its first correction can leave a residual slip (measured: 2 squares after (0, -4)).
TRACK_VERIFY_SHIFT = 2
# A re-solved pose this close to the last one has settled. Successive rounds from a good start differ by about
# the saddles' noise (0.03-0.08 deg): at 0.03 / 0.015 m 9 of 40 real tracked frames ran all rounds; at 0.05 / 0.025
# the real sample's calib took 19-20 instead of 30-33 ms per frame, rotation error median 0.014 instead of 0.013 deg,
# max 0.109 both (simulated complex, 8 x 40 frames: 22 / 25 instead of 25 / 29 ms median / mean, 0.008 / 0.203
# instead of 0.007 / 0.206 deg; scripts/bench_drone.py).
SETTLED_DEG, SETTLED_M = 0.05, 0.025
MAX_MOVE_SQUARES = 0.15  # a refined corner further than this from where a solved pose predicts it is no saddle
PREFILTER_CONTRAST = 0.5  # of min_contrast: what a saddle shows at its prediction to be refined at all


@dataclass
class SaddleMap:
    """Verification of the predicted (virtual) corners of one board, indices ``lo..hi`` beyond the board.

    ``ij`` (M, 2) virtual indices, ``uv`` (M, 2) refined image pixels, ``polarity`` (M,) +1 when the
    saddle has the colours corner ``ij`` should have, -1 when they are swapped, 0 when not a saddle.
    """

    board: Checkerboard
    ij: np.ndarray
    uv: np.ndarray
    polarity: np.ndarray


def saddle_map(
    gray: np.ndarray,
    camera: Camera,
    board: Checkerboard,
    px_per_square: float = 10.0,
    extend: int = 3,
    max_move_squares: float = MAX_MOVE_SQUARES,
    min_contrast: float = 20.0,
) -> SaddleMap:
    """Refine and verify every corner predicted by ``camera`` from ``-extend`` to ``n - 1 + extend``."""
    lo_i, lo_j = -extend, -extend
    hi_i, hi_j = board.nx - 1 + extend, board.ny - 1 + extend
    J, I = np.mgrid[lo_j : hi_j + 1, lo_i : hi_i + 1]
    ij = np.stack([I.ravel(), J.ravel()], axis=1)
    empty = SaddleMap(board, np.zeros((0, 2), int), np.zeros((0, 2)), np.zeros(0))
    world = board.points(ij[:, 0], ij[:, 1])
    front = camera.depth(world) > 0
    uv = np.full((len(ij), 2), np.nan)
    uv[front] = camera.project(world[front])
    ok = front & np.isfinite(uv).all(axis=1)
    ok[ok] = camera.in_image(uv[ok], margin=4.0)
    if not ok.any():
        return empty
    ij = ij[ok]
    # Rectified view: pixel (p, q) <-> corner coordinates (lo - 1 + p / s, lo - 1 + q / s).
    o_i, o_j = lo_i - 1.0, lo_j - 1.0
    size = (int(round((hi_i - o_i + 1) * px_per_square)), int(round((hi_j - o_j + 1) * px_per_square)))
    ij_H_rect = np.array([[1.0 / px_per_square, 0.0, o_i], [0.0, 1.0 / px_per_square, o_j], [0.0, 0.0, 1.0]])
    img_H_rect = image_H_board(camera, board) @ ij_H_rect
    rect = cv2.warpPerspective(gray, img_H_rect, size, flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
    pred = (ij - [o_i, o_j]) * px_per_square
    smooth = cv2.GaussianBlur(rect, (3, 3), 0).astype(np.float32)
    sign = board.cell_sign(ij[:, 0], ij[:, 1])
    refined, polarity = pred.astype(np.float64), np.zeros(len(ij), dtype=int)
    # From a solved pose a saddle is predicted within max_move_squares (< half the 0.3-square sampling offset),
    # so it already shows (weakly) at its prediction; the rest (most of the virtual corners beyond the board,
    # where cornerSubPix runs all its iterations on ground) are not refined at all. From a rough prior it may
    # not show yet: refine everything.
    todo = (
        _polarity(smooth, pred, px_per_square, min_contrast * PREFILTER_CONTRAST) != 0
        if max_move_squares <= MAX_MOVE_SQUARES
        else np.ones(len(ij), dtype=bool)
    )
    if todo.any():
        half = max(2, int(px_per_square * 0.4))
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01)
        refined[todo] = (
            cv2.cornerSubPix(
                rect, pred[todo].astype(np.float32).reshape(-1, 1, 2).copy(), (half, half), (-1, -1), criteria
            )
            .reshape(-1, 2)
            .astype(np.float64)
        )
        moved = np.linalg.norm(refined[todo] - pred[todo], axis=1) / px_per_square
        polarity[todo] = np.where(
            moved > max_move_squares, 0, _polarity(smooth, refined[todo], px_per_square, min_contrast) * sign[todo]
        )
    back = cv2.perspectiveTransform(refined.reshape(-1, 1, 2), img_H_rect).reshape(-1, 2)
    return SaddleMap(board, ij, back, polarity)


def _polarity(smooth: np.ndarray, pts: np.ndarray, px_per_square: float, min_contrast: float) -> np.ndarray:
    """(M,) +1 where the squares at -i-j / +i+j of each rectified pixel ``pts`` (M, 2) are light, -1 where
    they are dark, 0 where the four samples 0.3 squares around it are no saddle of ``min_contrast``."""
    d = 0.3 * px_per_square
    quad = []
    for dx, dy in ((-d, -d), (d, -d), (d, d), (-d, d)):
        p = (pts + [dx, dy]).astype(np.float32)
        quad.append(cv2.remap(smooth, p[:, 0].reshape(1, -1), p[:, 1].reshape(1, -1), cv2.INTER_LINEAR)[0])
    q = np.array(quad)
    # The square towards -i, -j of corner (i, j) is cell (i, j): light when its sign is +1.
    # A saddle needs BOTH squares of one diagonal brighter than both of the other: at the board's outer
    # edge two of the four samples are ground, which cancels in a plain diagonal difference but not here.
    light_first = np.minimum(q[0], q[2]) - np.maximum(q[1], q[3])
    dark_first = np.minimum(q[1], q[3]) - np.maximum(q[0], q[2])
    return np.where(light_first >= min_contrast, 1, np.where(dark_first >= min_contrast, -1, 0))


def saddle_counts(maps: list, max_shift: int = 2) -> dict:
    """(di, dj) -> number of verified saddles of the right colour that the board covers under that
    whole-square correction, for |di|, |dj| <= ``max_shift``.

    All boards share one correction (a camera translation moves every board alike); this assumes boards
    with the same square size and axes, as in MATRIX scenes.
    """
    shifts = np.array([(di, dj) for di in range(-max_shift, max_shift + 1) for dj in range(-max_shift, max_shift + 1)])
    parity = np.where(shifts.sum(axis=1) % 2 == 0, 1, -1)
    total = np.zeros(len(shifts), dtype=int)
    for m in maps:  # (shifts, corners) at once
        ti, tj = m.ij[None, :, 0] + shifts[:, :1], m.ij[None, :, 1] + shifts[:, 1:]
        inside = (ti >= 0) & (ti < m.board.nx) & (tj >= 0) & (tj < m.board.ny)
        total += np.sum(inside & (m.polarity[None, :] == parity[:, None]), axis=1)
    return {(int(di), int(dj)): int(n) for (di, dj), n in zip(shifts, total)}


def best_correction(maps: list, max_shift: int = 2, margin: int = 8) -> tuple:
    """(correction or None, saddles it covers): the whole-square correction the saddles support.

    The current assignment ``(0, 0)`` is kept unless another correction covers at least ``margin`` more
    saddles (a board edge in view); None when two different corrections both beat it but not each other
    by ``margin`` (ambiguous: the deciding edges are out of view).
    """
    counts = saddle_counts(maps, max_shift)
    ranked = sorted(counts, key=lambda d: (-counts[d], abs(d[0]) + abs(d[1])))
    best = ranked[0]
    if best == (0, 0) or counts[best] - counts[(0, 0)] < margin:
        return (0, 0), counts[(0, 0)]
    runner_up = ranked[1]
    if counts[best] - counts[runner_up] < margin:
        return None, counts[best]
    return best, counts[best]


def corrected_correspondences(maps: list, correction: tuple) -> tuple:
    """(N, 3) world points and (N, 2) pixels of the verified corners under ``correction``."""
    di, dj = correction
    parity = 1 if (di + dj) % 2 == 0 else -1
    world, uv = [], []
    for m in maps:
        t = m.ij + [di, dj]
        keep = (
            (t[:, 0] >= 0) & (t[:, 0] < m.board.nx) & (t[:, 1] >= 0) & (t[:, 1] < m.board.ny) & (m.polarity == parity)
        )
        world.append(m.board.points(t[keep, 0], t[keep, 1]))
        uv.append(m.uv[keep])
    return np.concatenate(world) if world else np.zeros((0, 3)), np.concatenate(uv) if uv else np.zeros((0, 2))


def _saddle_maps(
    gray: np.ndarray,
    camera: Camera,
    scene: CalibScene,
    settings: CalibSettings,
    max_move_squares: float = MAX_MOVE_SQUARES,
    max_shift: int = GROW_SHIFT,
) -> list:
    return [
        saddle_map(gray, camera, board, settings.px_per_square, extend=max_shift + 1, max_move_squares=max_move_squares)
        for board in scene.boards
    ]


def grow_pose(
    gray: np.ndarray,
    camera: Camera,
    scene: CalibScene,
    settings: CalibSettings,
    rounds: int = 1,
    start_move: float = MAX_MOVE_SQUARES,
    verify_shift: int = GROW_SHIFT,
):
    """(PnPResult or None, whole-square correction or None when ambiguous) of the (H, W) grey image, from
    the rough pose ``camera``.

    The grown pose is verified once more: at the final pose the saddles must put the board exactly
    where the pose does (correction (0, 0)); otherwise the correction counts as ambiguous (None).
    With ``rounds`` > 1 the pose is solved again from the saddles verified at the new pose until it
    settles: a rough starting pose verifies only the corners it predicts to a fraction of a square, and
    corners refined in a view rectified with a wrong pose are biased towards it (measured: a start
    0.2 deg off gave 0.1 deg after one round, 0.015 once settled). Each round is one more saddle pass.
    ``start_move``: the largest move (squares) of a verified corner in the first pass only, from ``camera``
    (a prediction a fraction of a square off needs more than the 0.15 of the passes from solved poses).
    ``verify_shift``: the largest whole-square slip checked at each solved pose."""
    maps = _saddle_maps(gray, camera, scene, settings, start_move)
    correction, count = best_correction(maps, GROW_SHIFT)
    if correction is None or count < settings.min_corners:
        return None, correction
    total, previous = (0, 0), camera
    for round_ in range(rounds):
        world, uv = corrected_correspondences(maps, correction)
        fit = solve_pnp(world, uv, scene.camera(np.eye(4)), settings.pnp_ransac_px)
        if fit is None:
            return None, correction
        total = (total[0] + correction[0], total[1] + correction[1])
        maps = _saddle_maps(gray, fit.camera, scene, settings, max_shift=verify_shift)
        correction, verified = best_correction(maps, verify_shift)
        if correction != (0, 0):
            return None, None
        # A fit from the looser first pass is never the answer: its corners may have converged off (measured:
        # real D2 frame 0, 0.12 deg instead of 0.06); the next round solves from the strict saddles.
        settled = (
            (round_ > 0 or start_move <= MAX_MOVE_SQUARES)
            and verified <= count * 1.02
            and rotation_angle_deg(fit.camera.R, previous.R) < SETTLED_DEG
            and np.linalg.norm(fit.camera.center - previous.center) < SETTLED_M
        )
        if settled or round_ == rounds - 1:
            return fit, total
        count, previous = verified, fit.camera
    return None, None  # not reached
