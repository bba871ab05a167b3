"""Metric bird's-eye-view grid on the ground plane."""

from dataclasses import dataclass

import numpy as np

from matrix_core.geometry.checks import as_points


@dataclass(frozen=True)
class BevGrid:
    """A regular grid of square cells on the ground plane (world metres).

    Convention:
        Cell ``(col, row)`` covers ``x in [x_min + col*cell, x_min + (col+1)*cell)`` and
        ``y in [y_min + row*cell, ...)``; its centre is at ``x_min + (col + 0.5) * cell``.
        Arrays over the grid have shape (rows, cols) = (ny, nx), row index along world y.
    """

    x_min: float
    y_min: float
    x_max: float
    y_max: float
    cell: float = 0.1

    def __post_init__(self):
        if not self.cell > 0:
            raise ValueError(f'cell must be positive, got {self.cell}')
        if not (self.x_max > self.x_min and self.y_max > self.y_min):
            raise ValueError(f'empty grid bounds x [{self.x_min}, {self.x_max}] y [{self.y_min}, {self.y_max}]')

    @property
    def nx(self) -> int:
        return int(round((self.x_max - self.x_min) / self.cell))

    @property
    def ny(self) -> int:
        return int(round((self.y_max - self.y_min) / self.cell))

    @property
    def shape(self) -> tuple:
        """(rows, cols) of arrays over the grid."""
        return (self.ny, self.nx)

    @property
    def ground_H_grid(self) -> np.ndarray:
        """(3, 3) homography from cell indices (col, row) to world metres of the cell centre."""
        c = self.cell
        return np.array([[c, 0.0, self.x_min + 0.5 * c], [0.0, c, self.y_min + 0.5 * c], [0.0, 0.0, 1.0]])

    def world_to_cell(self, xy) -> np.ndarray:
        """(N, 2) world metres -> (N, 2) continuous cell coordinates (col, row); centres are integers."""
        xy = as_points(xy, 2, 'xy')
        return (xy - [self.x_min, self.y_min]) / self.cell - 0.5

    def cell_to_world(self, colrow) -> np.ndarray:
        """(N, 2) continuous cell coordinates (col, row) -> (N, 2) world metres."""
        colrow = as_points(colrow, 2, 'colrow')
        return (colrow + 0.5) * self.cell + [self.x_min, self.y_min]

    def contains(self, xy) -> np.ndarray:
        """(N,) bool: which world points fall inside the grid bounds."""
        xy = as_points(xy, 2, 'xy')
        return (xy[:, 0] >= self.x_min) & (xy[:, 0] < self.x_max) & (xy[:, 1] >= self.y_min) & (xy[:, 1] < self.y_max)
