"""Shape and value checks shared by the geometry functions."""

import numpy as np


def as_points(points, dim: int, name: str = 'points') -> np.ndarray:
    """Return ``points`` as a float64 array of shape (N, dim); accepts a single point of shape (dim,)."""
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == dim:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise ValueError(f'{name} must have shape (N, {dim}), got {arr.shape}')
    return arr


def as_matrix(mat, shape: tuple, name: str) -> np.ndarray:
    """Return ``mat`` as a finite float64 array of exactly ``shape``."""
    arr = np.asarray(mat, dtype=np.float64)
    if arr.shape != shape:
        raise ValueError(f'{name} must have shape {shape}, got {arr.shape}')
    if not np.all(np.isfinite(arr)):
        raise ValueError(f'{name} contains NaN or infinite values')
    return arr
