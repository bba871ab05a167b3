"""Occlusion by boxes standing on the ground: the ONE exact line-of-sight test.

A point is hidden from a camera when the segment from the camera centre to it passes through the interior
of a box. The test works on the rays themselves (slab method), so it stays exact where a box reaches
behind the camera or close to its principal plane, where projecting the box's corners into the image
gives unbounded or meaningless polygons.

Convention: internal world metres, z up; a box is ``(x0, y0, x1, y1, height)`` with x0 < x1, y0 < y1,
standing on z = 0.
"""

import numpy as np

from matrix_core.geometry.checks import as_points


def as_boxes(boxes) -> np.ndarray:
    """(K, 5) float boxes ``x0 y0 x1 y1 height`` from a flat list of groups of 5 numbers or a (K, 5) array."""
    arr = np.asarray(boxes, dtype=np.float64)
    if arr.size % 5:
        raise ValueError(f'boxes must be groups of 5 numbers x0 y0 x1 y1 height, got {arr.size} numbers')
    return arr.reshape(-1, 5)


def segments_blocked(origin, targets, boxes) -> np.ndarray:
    """(N,) bool: whether the segment from ``origin`` (3,) to each of ``targets`` (N, 3) passes through any box.

    Slab test per segment, vectorised over the segments. A segment that only touches a face, or ends on
    one (a ground point at the foot of a wall), is not blocked; one that crosses the interior is, including
    a segment ending on the ground under a box (it enters through the top or a side). NaN targets are
    not blocked.

    Args:
        origin: (3,) start of every segment (the camera centre), world metres.
        targets: (N, 3) ends of the segments, world metres.
        boxes: boxes as accepted by :func:`as_boxes`.
    """
    targets = as_points(targets, 3, 'targets')
    origin = np.asarray(origin, dtype=np.float64).reshape(3)
    d = targets - origin
    # Axis-parallel segments: a tiny direction keeps the slab test valid (huge |t| outside the slab).
    d = np.where(np.abs(d) < 1e-12, 1e-12, d)
    blocked = np.zeros(len(targets), dtype=bool)
    for x0, y0, x1, y1, h in as_boxes(boxes):
        ta = (np.array([x0, y0, 0.0]) - origin) / d
        tb = (np.array([x1, y1, h]) - origin) / d
        t_near = np.minimum(ta, tb).max(axis=1)
        t_far = np.maximum(ta, tb).min(axis=1)
        blocked |= (t_near < t_far) & (t_far > 1e-9) & (t_near < 1.0 - 1e-9)
    return blocked
