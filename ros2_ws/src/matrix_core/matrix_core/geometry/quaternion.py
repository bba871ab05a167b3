"""Unit quaternions ``(x, y, z, w)`` (the field order of geometry_msgs/Quaternion) to and from (3, 3) rotations.

numpy only: scipy's ``Rotation`` does the same, but importing ``scipy.spatial`` took 0.5 s of the start of
every process that converts a pose (each drone's calib).
"""

import numpy as np

from matrix_core.geometry.checks import as_matrix


def quaternion_from_matrix(R: np.ndarray) -> np.ndarray:
    """(3, 3) rotation -> (4,) unit quaternion (x, y, z, w) with w >= 0 (Shepperd's method: the largest of
    the four squared components is computed first, so no division by a small number)."""
    R = as_matrix(R, (3, 3), 'R')
    trace = np.trace(R)
    i = int(np.argmax([R[0, 0], R[1, 1], R[2, 2], trace]))
    if i == 3:
        w = np.sqrt(1.0 + trace) / 2.0
        q = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1], 4.0 * w * w]) / (4.0 * w)
    else:
        j, k = (i + 1) % 3, (i + 2) % 3
        s = np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k]) / 2.0  # the i-th component
        q = np.empty(4)
        q[i] = s
        q[j] = (R[j, i] + R[i, j]) / (4.0 * s)
        q[k] = (R[k, i] + R[i, k]) / (4.0 * s)
        q[3] = (R[k, j] - R[j, k]) / (4.0 * s)
    q /= np.linalg.norm(q)
    return -q if q[3] < 0 else q


def matrix_from_quaternion(q) -> np.ndarray:
    """(4,) quaternion (x, y, z, w), normalised here -> (3, 3) rotation. A zero quaternion is an error."""
    q = np.asarray(q, dtype=np.float64).reshape(-1)
    norm = np.linalg.norm(q) if q.shape == (4,) else 0.0
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError(f'a quaternion needs 4 finite values, not all 0; got {q.tolist()}')
    x, y, z, w = q / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
