"""Constant-velocity Kalman filter on the ground plane.

Convention: state ``[x, y, vx, vy]`` in metres and metres/second (world frame), measurement ``[x, y]``.
Process noise is the white-noise-acceleration model with std ``accel_noise`` (m/s^2).
"""

import numpy as np

_H = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])


class ConstantVelocityKalman:
    """Filter parameters shared by all tracks; each track keeps its own ``(mean (4,), cov (4, 4))``."""

    def __init__(self, dt: float, accel_noise: float, measurement_noise: float):
        self.F = np.eye(4)
        self.F[0, 2] = self.F[1, 3] = dt
        q = np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]]) * accel_noise**2
        self.Q = np.zeros((4, 4))
        self.Q[np.ix_([0, 2], [0, 2])] = q
        self.Q[np.ix_([1, 3], [1, 3])] = q
        self.R = np.eye(2) * measurement_noise**2
        self.dt = dt

    def initiate(self, xy, velocity=None) -> tuple:
        """New state at a measured position; unknown velocity gets a 2 m/s std."""
        mean = np.r_[np.asarray(xy, float), np.zeros(2) if velocity is None else np.asarray(velocity, float)]
        cov = np.diag([self.R[0, 0], self.R[1, 1], 4.0, 4.0])
        if velocity is not None:
            cov[2:, 2:] = np.eye(2) * (2 * self.R[0, 0] / self.dt**2)
        return mean, cov

    def predict(self, mean, cov) -> tuple:
        """State one frame later."""
        return self.F @ mean, self.F @ cov @ self.F.T + self.Q

    def update(self, mean, cov, xy) -> tuple:
        """Posterior after measuring position ``xy`` (2,)."""
        S = _H @ cov @ _H.T + self.R
        K = cov @ _H.T @ np.linalg.inv(S)
        mean = mean + K @ (np.asarray(xy, float) - _H @ mean)
        cov = (np.eye(4) - K @ _H) @ cov
        return mean, cov
