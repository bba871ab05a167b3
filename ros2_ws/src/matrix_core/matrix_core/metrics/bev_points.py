"""Ground-plane points over time (detections, tracks or ground truth) and their plain-text format.

Convention:
    - positions are world metres in the internal frame (right-handed, z up, see ``geometry/camera.py``);
    - ``frame`` is an integer time step; rows of one frame need not be contiguous in a file;
    - text lines (whitespace separated, ``#`` starts a comment, blank lines ignored):
        detections ``frame x y score``    (``score`` optional, default 1.0)
        tracks / ground truth ``frame id x y``
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matrix_core.output_paths import atomic_write_text


@dataclass(frozen=True)
class BevPoints:
    """N points on the ground, each at one frame.

    Attributes:
        frames: (N,) int64 time steps.
        xy: (N, 2) float64 world metres.
        ids: (N,) int64 identities, or None for anonymous detections.
        scores: (N,) float64 confidences (1.0 where the source has none).
    """

    frames: np.ndarray
    xy: np.ndarray
    ids: np.ndarray = None
    scores: np.ndarray = None

    def __post_init__(self):
        frames = np.asarray(self.frames, dtype=np.int64).reshape(-1)
        xy = np.asarray(self.xy, dtype=np.float64).reshape(-1, 2)
        n = len(frames)
        if len(xy) != n:
            raise ValueError(f'frames ({n}) and xy ({len(xy)}) differ in length')
        if not np.all(np.isfinite(xy)):
            raise ValueError('positions contain NaN or infinite values')
        ids = None if self.ids is None else np.asarray(self.ids, dtype=np.int64).reshape(-1)
        if ids is not None and len(ids) != n:
            raise ValueError(f'ids ({len(ids)}) and frames ({n}) differ in length')
        scores = np.ones(n) if self.scores is None else np.asarray(self.scores, dtype=np.float64).reshape(-1)
        if len(scores) != n:
            raise ValueError(f'scores ({len(scores)}) and frames ({n}) differ in length')
        object.__setattr__(self, 'frames', frames)
        object.__setattr__(self, 'xy', xy)
        object.__setattr__(self, 'ids', ids)
        object.__setattr__(self, 'scores', scores)

    def __len__(self) -> int:
        return len(self.frames)

    @property
    def has_ids(self) -> bool:
        return self.ids is not None

    @property
    def frame_numbers(self) -> np.ndarray:
        """Sorted unique frames that have at least one point."""
        return np.unique(self.frames)

    def at(self, frame: int) -> np.ndarray:
        """Row indices of ``frame``, in file order."""
        return np.flatnonzero(self.frames == frame)

    def by_frame(self) -> dict:
        """frame -> row indices (file order), for every frame that has points."""
        return rows_by_frame(self.frames)


def rows_by_frame(frames) -> dict:
    """frame -> row indices (file order) of (N,) int ``frames``, for every frame that occurs."""
    frames = np.asarray(frames).reshape(-1)
    order = np.argsort(frames, kind='stable')
    cuts = np.flatnonzero(np.diff(frames[order])) + 1
    # key by the frame of each group's first ROW (not the sorted position): rows need not be in frame order
    return {int(frames[g[0]]): g for g in np.split(order, cuts) if len(g)} if len(order) else {}


def read_bev_points(path, with_ids: bool = None) -> BevPoints:
    """Read a detections (``frame x y [score]``) or tracks (``frame id x y``) text file.

    Args:
        path: text file.
        with_ids: True: ``frame id x y``; False: ``frame x y [score]``; None: decide from the column count
            (4 columns with an integer second column -> tracks).

    Raises:
        FileNotFoundError, ValueError (with file and line number) on malformed content.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'no such file: {path}')
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        text = line.split('#', 1)[0].strip()
        if not text:
            continue
        try:
            rows.append([float(v) for v in text.split()])
        except ValueError:
            raise ValueError(f'{path}:{number}: not numbers: {line!r}') from None
        if len(rows[-1]) not in (3, 4) or not np.all(np.isfinite(rows[-1])):
            raise ValueError(f'{path}:{number}: expected 3 or 4 finite numbers, got {line!r}')
    widths = {len(r) for r in rows}
    if len(widths) > 1:
        raise ValueError(f'{path}: lines mix 3 and 4 columns')
    table = np.array(rows, dtype=np.float64).reshape(-1, widths.pop() if widths else 4)
    if with_ids is None:
        with_ids = table.shape[1] == 4 and np.all(table[:, 1] == np.round(table[:, 1]))
    if np.any(table[:, 0] != np.round(table[:, 0])):
        raise ValueError(f'{path}: frame numbers (first column) must be integers')
    if with_ids:
        if table.shape[1] != 4 or np.any(table[:, 1] != np.round(table[:, 1])):
            raise ValueError(f'{path}: expected lines "frame id x y" with integer ids')
        return BevPoints(table[:, 0], table[:, 2:4], ids=table[:, 1])
    scores = table[:, 3] if table.shape[1] == 4 else None
    return BevPoints(table[:, 0], table[:, 1:3], scores=scores)


def bev_point_lines(points: BevPoints) -> str:
    """The text of ``points`` in their order, a line each: ``frame id x y`` (points with ids) or
    ``frame x y score`` (what :func:`read_bev_points` reads; written whole or a frame at a time)."""
    lines = []
    for i in range(len(points)):
        x, y = points.xy[i]
        if points.has_ids:
            lines.append(f'{points.frames[i]} {points.ids[i]} {x:.4f} {y:.4f}\n')
        else:
            lines.append(f'{points.frames[i]} {x:.4f} {y:.4f} {points.scores[i]:.4f}\n')
    return ''.join(lines)


def write_bev_points(path, points: BevPoints) -> None:
    """Write the lines of :func:`bev_point_lines`, sorted by frame (stable)."""
    order = np.argsort(points.frames, kind='stable')
    ids = None if points.ids is None else points.ids[order]
    atomic_write_text(
        path, bev_point_lines(BevPoints(points.frames[order], points.xy[order], ids, points.scores[order]))
    )
