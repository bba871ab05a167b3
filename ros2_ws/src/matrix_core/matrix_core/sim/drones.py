"""Drone motion and the PID-aimed camera gimbal (the MATRIX paper's control loop).

Each drone flies under velocity-based position control toward random targets within +-``target_xy`` m of
its home position in x and y and within a ``target_z_band`` m band around ``altitude`` (speed <= ``v_max``,
acceleration <= ``max_accel``); a new target comes every ``retarget_period`` seconds or when one is reached,
which gives the back-and-forth oscillation of the real drones. A multicopter tilts by atan(a / g) to
accelerate; that body tilt (lagged by ``tilt_lag_s``) reaches the camera (roll directly, pitch as a
disturbance) and a PID loop with the paper's gains (Kp = 0.0002, Ki = 0.00002, Kd = 0.0001, output in
radians per 0.05 s control tick) turns the gimbal in yaw and pitch to bring the aimed point (the scene
centre plus a slowly wandering offset) back to the image centre. The pixel error is measured in pixels of
the 1920-wide reference camera, so the motion does not depend on the render resolution.

Convention: internal world frame; yaw is the heading of the optical axis from +x counter-clockwise, pitch
is the angle of the optical axis below the horizon (positive looks down), roll turns the image clockwise
about the optical axis. The camera frame is OpenCV's optical frame.
"""

from dataclasses import dataclass, field

import numpy as np

from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.reference_size import REFERENCE_WIDTH

GRAVITY = 9.81
CONTROL_DT = 0.05  # seconds per control tick
AIM_RELAX_S = 3.0  # time constant of the wandering aimed point
# Home directions of D1..D8 in the internal frame, from the real reference poses (file y is negated).
HOME_DIRECTIONS = np.array([[-1, 1], [0, 1], [1, 1], [1, 0], [1, -1], [0, -1], [-1, -1], [-1, 0]], dtype=float)


def intrinsics(width: int, height: int, hfov_deg: float) -> np.ndarray:
    """(3, 3) ideal pinhole K for the internal pixel-centre convention: f from the horizontal field of view,
    principal point at the image centre ((W - 1) / 2, (H - 1) / 2), like MATRIX's cx = 960 in file pixels."""
    f = (width / 2.0) / np.tan(np.radians(hfov_deg) / 2.0)
    return np.array([[f, 0.0, (width - 1) / 2.0], [0.0, f, (height - 1) / 2.0], [0.0, 0.0, 1.0]])


def camera_rotation(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """(3, 3) ``cam_R_world`` (rows: camera x, y, z axes in world coordinates) from yaw, pitch, roll (rad)."""
    forward = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), -np.sin(pitch)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    c, s = np.cos(roll), np.sin(roll)
    x_cam, y_cam = c * right + s * down, -s * right + c * down
    return np.stack([x_cam, y_cam, forward])


def look_at_angles(center: np.ndarray, target: np.ndarray) -> tuple:
    """(yaw, pitch) in radians that point the optical axis from ``center`` to ``target`` (both (3,))."""
    d = np.asarray(target, float) - np.asarray(center, float)
    return float(np.arctan2(d[1], d[0])), float(np.arctan2(-d[2], np.hypot(d[0], d[1])))


@dataclass(frozen=True)
class DroneRig:
    """A site's drones (``sim/site_rig.py``): where each hovers and the camera it carries, instead of the
    MATRIX ring of eight drones with one camera.

    Attributes:
        names: (N,) drone names, the view names.
        homes: (N, 3) metres: the point each drone's random targets are drawn around.
        K: (N,) (3, 3) intrinsics at the rendered image size, pixel-centre convention.
        sizes: (N,) (width, height) of the rendered images.
        references: (N,) the :class:`Camera` of each drone's reference image, or None: the reference pose is
            then the home, aimed exactly at the scene centre.
    """

    names: tuple
    homes: np.ndarray
    K: tuple
    sizes: tuple
    references: tuple


@dataclass
class DroneState:
    """State of one drone. position/velocity: (3,) metres, m/s; angles in radians."""

    home: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    target: np.ndarray
    aim_offset: np.ndarray  # (3,) metres added to the aimed scene centre
    aim_goal: np.ndarray  # aim_offset relaxes toward this (no jumps in the aimed point)
    retarget_in: float  # seconds until a new target is drawn even if the current one is not reached
    yaw: float
    pitch: float
    roll: float = 0.0
    accel: np.ndarray = field(default_factory=lambda: np.zeros(3))
    body_pitch: float = 0.0
    err_sum: np.ndarray = None
    err_prev: np.ndarray = None


class DroneFleet:
    """The drones of a scene; :meth:`step` advances all of them by one frame period.

    Args:
        config: :class:`~matrix_core.sim.config.DroneConfig`.
        center: (2,) scene centre (x, y) metres; the cameras aim at (center, 0) plus a wandering offset.
        rng: random generator used only for targets and aim offsets (deterministic per seed).
        rig: a site's :class:`DroneRig` (its homes, cameras and reference poses), or None for the MATRIX ring
            (``config.count`` <= 8 drones, ``config.hfov_deg`` cameras at the size each call asks for).
    """

    def __init__(self, config, center, rng: np.random.Generator, rig: DroneRig = None):
        self.config = config
        self.center = np.array([center[0], center[1], 0.0])
        self.rng = rng
        self.rig = rig
        if rig is None and config.count > len(HOME_DIRECTIONS):
            raise ValueError(
                f'the MATRIX ring has {len(HOME_DIRECTIONS)} places (D1..D8), got {config.count} drones; '
                f'more drones need a site (simulate --site)'
            )
        self.K_ref = intrinsics(REFERENCE_WIDTH, REFERENCE_WIDTH * 9 // 16, config.hfov_deg)
        self.drones = []
        for k in range(config.count if rig is None else len(rig.names)):
            if rig is None:
                home = np.array([*(self.center[:2] + config.ring_half_side * HOME_DIRECTIONS[k]), config.altitude])
            else:
                home = np.asarray(rig.homes[k], dtype=float)
            start = self._random_target(home)
            yaw, pitch = look_at_angles(start, self.center)
            self.drones.append(
                DroneState(
                    home,
                    start,
                    np.zeros(3),
                    self._random_target(home),
                    np.zeros(3),
                    self._random_aim(),
                    self._retarget_time(),
                    yaw,
                    pitch,
                    err_sum=np.zeros(2),
                    err_prev=np.zeros(2),
                )
            )

    def _random_target(self, home: np.ndarray) -> np.ndarray:
        c = self.config
        return home + np.array(
            [
                self.rng.uniform(-c.target_xy, c.target_xy),
                self.rng.uniform(-c.target_xy, c.target_xy),
                self.rng.uniform(-c.target_z_band / 2, c.target_z_band / 2),
            ]
        )

    def _retarget_time(self) -> float:
        lo, hi = self.config.retarget_period
        return float(self.rng.uniform(lo, hi))

    def _random_aim(self) -> np.ndarray:
        j = self.config.aim_jitter
        return np.array([self.rng.uniform(-j, j), self.rng.uniform(-j, j), 0.0])

    def reference_camera(self, index: int, width: int, height: int) -> Camera:
        """Static reference pose of drone ``index`` (``reference_ring_half_side``, ``reference_altitude``),
        aimed exactly at the scene centre: the view of the ``reference/`` folder, as in the real sample.
        With a rig: its reference camera of that drone, else its home aimed at the centre, at the rig's size."""
        c = self.config
        if self.rig is not None:
            if self.rig.references[index] is not None:
                return self.rig.references[index]
            pos = np.asarray(self.rig.homes[index], dtype=float)
        else:
            pos = np.array(
                [*(self.center[:2] + c.reference_ring_half_side * HOME_DIRECTIONS[index]), c.reference_altitude]
            )
        yaw, pitch = look_at_angles(pos, self.center)
        return self._camera(pos, camera_rotation(yaw, pitch, 0.0), width, height, index)

    def camera(self, index: int, width: int, height: int) -> Camera:
        """Current camera of drone ``index`` at the given render size (same pose at every size); with a rig, at
        the rig's intrinsics and size of that drone (``width``, ``height`` are not used)."""
        d = self.drones[index]
        return self._camera(d.position, camera_rotation(d.yaw, d.pitch + d.body_pitch, d.roll), width, height, index)

    def _camera(self, position, cam_R_world, width, height, index: int) -> Camera:
        if self.rig is not None:
            (width, height), K = self.rig.sizes[index], self.rig.K[index]
        else:
            K = intrinsics(width, height, self.config.hfov_deg)
        return Camera(K, pose_matrix(cam_R_world, -cam_R_world @ position), width, height)

    def step(self, duration: float) -> None:
        """Advance every drone by ``duration`` seconds in ticks of :data:`CONTROL_DT`."""
        for _ in range(int(round(duration / CONTROL_DT))):
            for d in self.drones:
                self._tick(d)

    def _tick(self, d: DroneState) -> None:
        c, dt = self.config, CONTROL_DT
        d.retarget_in -= dt
        if d.retarget_in <= 0 or np.linalg.norm(d.target - d.position) < 0.3:
            d.target = self._random_target(d.home)
            d.aim_goal = self._random_aim()
            d.retarget_in = self._retarget_time()
        d.aim_offset = d.aim_offset + (d.aim_goal - d.aim_offset) * (dt / AIM_RELAX_S)
        v_cmd = c.position_gain * (d.target - d.position)
        speed = np.linalg.norm(v_cmd)
        if speed > c.v_max:
            v_cmd *= c.v_max / speed
        accel = (v_cmd - d.velocity) / dt
        a_norm = np.linalg.norm(accel)
        if a_norm > c.max_accel:
            accel *= c.max_accel / a_norm
        # Attitude follows the commanded acceleration with a first-order lag (no instant tilt flips).
        d.accel = d.accel + (accel - d.accel) * min(1.0, dt / c.tilt_lag_s)
        accel = d.accel
        d.velocity = d.velocity + accel * dt
        v_norm = np.linalg.norm(d.velocity)
        if v_norm > c.v_max:
            d.velocity *= c.v_max / v_norm
        d.position = d.position + d.velocity * dt
        # Body tilt from the horizontal acceleration, seen in the camera's heading frame.
        fwd = np.array([np.cos(d.yaw), np.sin(d.yaw)])
        left = np.array([-fwd[1], fwd[0]])
        d.body_pitch = float(np.arctan2(accel[:2] @ fwd, GRAVITY))
        d.roll = float(np.arctan2(accel[:2] @ left, GRAVITY))
        # Gimbal PID on the pixel error of the aimed point (reference-resolution pixels).
        R = camera_rotation(d.yaw, d.pitch + d.body_pitch, d.roll)
        p_cam = R @ (self.center + d.aim_offset - d.position)
        if p_cam[2] <= 0.1:  # aimed point behind the camera: cannot happen on the ring; reset the gimbal
            d.yaw, d.pitch = look_at_angles(d.position, self.center)
            d.err_sum[:], d.err_prev[:] = 0.0, 0.0
            return
        err = self.K_ref[0, 0] * p_cam[:2] / p_cam[2]
        d.err_sum += err
        out = c.kp * err + c.ki * d.err_sum + c.kd * (err - d.err_prev)
        d.err_prev = err
        d.yaw -= out[0]
        d.pitch += out[1]
