"""Which board corner is each detected corner? The prior predicts it approximately, the board's checker
colours and edges decide the exact offset; ambiguous pieces are rejected.

A detected piece (its corners on a grid of (column, row) positions) can be any of the 8 grid symmetries
and any offset that keeps it inside the board, on either board: every such hypothesis fits the image
equally well (the pattern is periodic and symmetric). Moving the hypothesis by one square moves the camera
by one square (0.25 m), about as far as a drone flies between frames, so the pose prior alone cannot
decide. Here:

1. the prior homography of each board (image pixels -> fractional corner coordinates (i, j), from
   :func:`matrix_core.calib.regions.image_H_board`) maps the piece onto the board: the orientation is the
   symmetry that best agrees with those coordinates, and offsets within ``max_index_error`` squares of the
   predicted one are candidates;
2. PnP (IPPE) of the piece gives a pose for one hypothesis; a shift by (di, dj) squares only moves the
   camera by that world vector, so the image of the whole board is known under every candidate. Squares
   are sampled at their projected centres and correlated with the board's light/dark pattern: odd shifts
   swap the colours (negative score), shifts that move the board edge leave ground inside it (lower score);
3. a candidate scoring at least ``ambiguity_ratio`` of the best is a rival; rivals are separated by the
   prior (predicted offset) if one is closer by ``index_separation`` squares, otherwise the piece is
   rejected as ambiguous.
"""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.calib.board import Checkerboard
from matrix_core.calib.detection import GridPiece
from matrix_core.geometry.camera import Camera, pose_matrix, rotation_angle_deg

# The 8 symmetries of a square grid as (c, r) -> (i, j) integer matrices.
_ORIENTATIONS = [
    np.array(m)
    for m in (
        [[1, 0], [0, 1]],
        [[-1, 0], [0, 1]],
        [[1, 0], [0, -1]],
        [[-1, 0], [0, -1]],
        [[0, 1], [1, 0]],
        [[0, -1], [1, 0]],
        [[0, 1], [-1, 0]],
        [[0, -1], [-1, 0]],
    )
]


@dataclass
class Assignment:
    """Result for one piece: board, (N, 2) int corner indices (i, j), (N, 2) pixels, and evidence."""

    board: Checkerboard
    indices: np.ndarray
    image_uv: np.ndarray
    score: float
    runner_up_ratio: float
    decided_by_prior: bool

    @property
    def world(self) -> np.ndarray:
        """(N, 3) world metres of the assigned corners."""
        return self.board.points(self.indices[:, 0], self.indices[:, 1])


def _pose_ippe(world: np.ndarray, uv: np.ndarray, camera: Camera):
    ok, rvec, tvec = cv2.solvePnP(
        world.reshape(-1, 1, 3), uv.reshape(-1, 1, 2), camera.K, camera.dist, flags=cv2.SOLVEPNP_IPPE
    )
    if not ok or not (np.all(np.isfinite(rvec)) and np.all(np.isfinite(tvec))):  # degenerate (e.g. collinear) grid
        return None
    R = cv2.Rodrigues(rvec)[0]
    proj, _ = cv2.projectPoints(world.reshape(-1, 1, 3), rvec, tvec, camera.K, camera.dist)
    rms = float(np.sqrt(np.mean(np.sum((proj.reshape(-1, 2) - uv) ** 2, axis=1))))
    return R, tvec.reshape(3), rms


def _sample(image: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear samples of a float32 image at (N, 2) pixels (pixel-centre convention)."""
    m = uv.astype(np.float32).reshape(1, -1, 2)
    return cv2.remap(image, m[..., 0], m[..., 1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)[0]


def _offset_scores(board, indices0, R, t0, camera, smooth) -> tuple:
    """(M, 2) offsets keeping the piece on the board and their checker-pattern scores (M,)."""
    lo, hi = indices0.min(axis=0), indices0.max(axis=0)
    di = np.arange(-lo[0], board.nx - 1 - hi[0] + 1)
    dj = np.arange(-lo[1], board.ny - 1 - hi[1] + 1)
    if len(di) == 0 or len(dj) == 0:
        return np.zeros((0, 2), int), np.zeros(0)
    # Virtual cells (a, b) of the offset-0 frame covering every hypothesis' board: a = cell - di.
    a = np.arange(0 - di.max(), board.nx + 1 - di.min())
    b = np.arange(0 - dj.max(), board.ny + 1 - dj.min())
    A, B = np.meshgrid(a, b, indexing='ij')
    centres = board.points(A.ravel() - 0.5, B.ravel() - 0.5)
    cam = Camera(camera.K, pose_matrix(R, t0), camera.width, camera.height, camera.dist)
    valid = cam.depth(centres) > 0
    uv = np.full((len(centres), 2), -1e6)
    uv[valid] = cam.project(centres[valid])
    valid &= cam.in_image(uv, margin=2.0)
    values = np.zeros(len(centres), dtype=np.float64)
    if valid.any():
        values[valid] = _sample(smooth, uv[valid])
        values[valid] -= np.median(values[valid])
    V = values.reshape(A.shape)
    ta, tb = np.meshgrid(np.arange(board.nx + 1), np.arange(board.ny + 1), indexing='ij')
    template = board.cell_sign(ta, tb).astype(np.float64)
    corr = correlate_valid(V, template)  # corr[k, l]: board cell (a, b) <- V[a + k, b + l]
    # V index p holds virtual cell a[p]; board cell x of offset d sits at virtual x - d, i.e. k = -d - a[0].
    K_, L_ = np.meshgrid(-di - a[0], -dj - b[0], indexing='ij')
    D_i, D_j = np.meshgrid(di, dj, indexing='ij')
    return np.stack([D_i.ravel(), D_j.ravel()], axis=1), corr[K_.ravel(), L_.ravel()]


def correlate_valid(values: np.ndarray, template: np.ndarray) -> np.ndarray:
    """2-D cross-correlation, valid part only: (M, N) ``values``, (m, n) ``template`` -> (M - m + 1, N - n + 1),
    out[k, l] = sum over (a, b) of values[k + a, l + b] * template[a, b] (scipy.signal.correlate2d, mode 'valid',
    whose import alone took 2 s of each drone process's start on a 2-core machine)."""
    windows = np.lib.stride_tricks.sliding_window_view(values, template.shape)
    return np.einsum('klab,ab->kl', windows, template)


def assign_piece(
    piece: GridPiece,
    boards: list,
    predicted: dict,
    prior: Camera,
    smooth: np.ndarray,
    max_index_error: float = 2.5,
    ambiguity_ratio: float = 0.95,
    index_separation: float = 0.6,
    max_prior_rotation_deg: float = 35.0,
    max_fit_rms_px: float = 1.5,
    max_orientation_residual: float = 0.5,
):
    """Assign board corners to ``piece`` (see the module docstring).

    Args:
        piece: the detected grid.
        boards: candidate :class:`Checkerboard` list.
        predicted: board name -> (3, 3) homography image pixels -> predicted corner coordinates (i, j).
        prior: camera with the prior pose and the intrinsics to use.
        smooth: (H, W) float32 grey image, slightly blurred (checker colour samples).
        max_index_error: candidates are offsets within this many squares of the predicted one.
        max_orientation_residual: median distance (squares) between predicted and hypothesised corner
            coordinates, after the best offset, for an orientation to be considered.

    Returns:
        (:class:`Assignment` or None, reason string).
    """
    cr, uv = piece.grid_cr, piece.uv
    cands = []  # (score, prior distance in squares, board, indices)
    reasons = set()
    for board in boards:
        if board.name not in predicted:
            continue
        ij_pred = cv2.perspectiveTransform(uv.reshape(-1, 1, 2), predicted[board.name]).reshape(-1, 2)
        board_z = float(np.asarray(board.origin)[2])
        for O in _ORIENTATIONS:
            base = cr @ O.T
            off_pred = np.median(ij_pred - base, axis=0)
            resid = np.median(np.linalg.norm(ij_pred - base - np.round(off_pred), axis=1))
            if resid > max_orientation_residual + 0.71:  # + half a diagonal: the rounding itself
                continue
            lo, hi = base.min(axis=0), base.max(axis=0)
            if hi[0] - lo[0] >= board.nx or hi[1] - lo[1] >= board.ny:
                continue
            fit = _pose_ippe(board.points(base[:, 0], base[:, 1]), uv, prior)
            if fit is None:
                continue
            R, t0, rms = fit
            if rms > max_fit_rms_px:
                reasons.add(f'grid fits a board plane with {rms:.1f} px RMS (bad grid)')
                continue
            if rotation_angle_deg(R, prior.R) > max_prior_rotation_deg or (-R.T @ t0)[2] <= board_z:
                reasons.add('orientation disagrees with the prior')
                continue
            offsets, scores = _offset_scores(board, base, R, t0, prior, smooth)
            dist = np.abs(offsets - off_pred).max(axis=1)
            near = dist <= max_index_error
            if not near.any():
                reasons.add('predicted position off the board')
            for k in np.flatnonzero(near):
                cands.append((float(scores[k]), float(dist[k]), board, base + offsets[k]))
    if not cands:
        return None, '; '.join(sorted(reasons)) or 'no board predicted near the piece'
    cands.sort(key=lambda x: -x[0])
    best = cands[0][0]
    if best <= 0:
        return None, 'no checker colour evidence'
    rivals = [x for x in cands if x[0] >= ambiguity_ratio * best]
    runner_up = cands[1][0] / best if len(cands) > 1 else 0.0
    chosen, by_prior = rivals[0], False
    if len(rivals) > 1:
        rivals.sort(key=lambda x: x[1])
        if rivals[1][1] - rivals[0][1] < index_separation:
            return None, f'ambiguous: {len(rivals)} assignments score within {ambiguity_ratio:.2f} of the best'
        chosen, by_prior = rivals[0], True
    score, _, board, indices = chosen
    return Assignment(board, indices.astype(int), uv.copy(), score, float(runner_up), by_prior), 'ok'
