"""Planar checkerboards lying on the ground: the 3-D points of their inner corners and squares.

Convention:
    - inner corner ``(i, j)``, ``i = 0..nx-1``, ``j = 0..ny-1`` lies at
      ``origin + square * (i * axis_i + j * axis_j)`` in internal world metres (right-handed, z up);
    - square (cell) ``(a, b)``, ``a = 0..nx``, ``b = 0..ny``, is bounded by corners ``a-1..a`` and
      ``b-1..b``; its centre is at corner coordinates ``(a - 0.5, b - 0.5)``;
    - cell ``(0, 0)`` is light when ``first_cell_light``; colours alternate, so cell ``(a, b)`` is light
      exactly when ``(a + b)`` is even (for ``first_cell_light``).
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Checkerboard:
    """One board. ``origin`` (3,) metres, ``axis_i``/``axis_j`` (3,) unit vectors in the board plane."""

    name: str
    origin: tuple
    square: float
    inner_corners: tuple  # (nx, ny)
    axis_i: tuple = (1.0, 0.0, 0.0)
    axis_j: tuple = (0.0, 1.0, 0.0)
    first_cell_light: bool = True

    def __post_init__(self):
        if self.square <= 0:
            raise ValueError(f'board {self.name}: square must be positive, got {self.square}')
        if len(self.inner_corners) != 2 or min(self.inner_corners) < 2:
            raise ValueError(f'board {self.name}: inner_corners must be (nx, ny) >= 2, got {self.inner_corners}')
        u, v = np.asarray(self.axis_i, float), np.asarray(self.axis_j, float)
        if (
            u.shape != (3,)
            or v.shape != (3,)
            or abs(np.linalg.norm(u) - 1) > 1e-6
            or abs(np.linalg.norm(v) - 1) > 1e-6
            or abs(u @ v) > 1e-6
        ):
            raise ValueError(f'board {self.name}: axis_i and axis_j must be orthonormal 3-vectors')
        if len(self.origin) != 3:
            raise ValueError(f'board {self.name}: origin must be (x, y, z)')

    @property
    def nx(self) -> int:
        return int(self.inner_corners[0])

    @property
    def ny(self) -> int:
        return int(self.inner_corners[1])

    def points(self, i, j) -> np.ndarray:
        """World metres of (possibly fractional or out-of-board) corner coordinates: (N,) i, j -> (N, 3)."""
        i = np.asarray(i, dtype=np.float64).reshape(-1, 1)
        j = np.asarray(j, dtype=np.float64).reshape(-1, 1)
        return np.asarray(self.origin, float) + self.square * (
            i * np.asarray(self.axis_i, float) + j * np.asarray(self.axis_j, float)
        )

    def corner_indices(self) -> np.ndarray:
        """(nx * ny, 2) int (i, j) of every inner corner (i varies fastest)."""
        j, i = np.mgrid[0 : self.ny, 0 : self.nx]
        return np.stack([i.ravel(), j.ravel()], axis=1)

    def corners_world(self) -> np.ndarray:
        """(nx * ny, 3) world metres of every inner corner, in :meth:`corner_indices` order."""
        ij = self.corner_indices()
        return self.points(ij[:, 0], ij[:, 1])

    def cell_sign(self, a, b) -> np.ndarray:
        """+1 for light, -1 for dark cells (a, b) (arrays); meaningful for cells on the board only."""
        s = 1 - 2 * ((np.asarray(a) + np.asarray(b)) % 2)
        return s if self.first_cell_light else -s
