"""Pinhole camera model: the ONE geometric convention everything downstream of the data readers uses.

Convention:
    - ``world``: right-handed, metres, z up, the ground is the plane z = 0.
    - ``cam``: OpenCV optical frame, x right, y down, z forward (right-handed).
    - image pixels ``img``: OpenCV pixel-centre convention: (0, 0) is the CENTRE of the top-left pixel,
      u to the right, v down; the image is as stored on disk (never mirrored).
    - ``cam_T_world`` (4, 4) maps homogeneous world points into the camera frame; its rotation is a
      proper rotation (det +1).
    - lens distortion, when present, is OpenCV's 5-coefficient model (k1, k2, p1, p2, k3).

Dataset-specific conventions (MATRIX's mirrored image and left-handed world, Wildtrack's centimetres, ...)
are converted into this one by the readers in ``matrix_core.datasets`` and back by the writer.
"""

from dataclasses import dataclass, field

import cv2
import numpy as np

from matrix_core.geometry.checks import as_matrix, as_points
from matrix_core.geometry.homography import apply_homography, ground_homography


def pose_matrix(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(4, 4) homogeneous transform from a (3, 3) rotation and a (3,) translation."""
    T = np.eye(4)
    T[:3, :3] = as_matrix(R, (3, 3), 'R')
    T[:3, 3] = as_matrix(np.reshape(t, 3), (3,), 't')
    return T


def invert_pose(a_T_b: np.ndarray) -> np.ndarray:
    """Inverse of a rigid (4, 4) transform: returns ``b_T_a``."""
    a_T_b = as_matrix(a_T_b, (4, 4), 'a_T_b')
    R, t = a_T_b[:3, :3], a_T_b[:3, 3]
    return pose_matrix(R.T, -R.T @ t)


def check_intrinsics(K, dist=None, size=None, what: str = 'intrinsics') -> np.ndarray:
    """The one validity rule of intrinsics: ``K`` (3, 3) finite and non-singular, ``dist`` (N,) finite, ``size``
    (w, h) positive. Returns K as float64 (3, 3); raises ValueError naming ``what`` and the fault."""
    K = np.asarray(K, dtype=np.float64)
    if K.size != 9 or not np.all(np.isfinite(K)):
        raise ValueError(f'{what}: K has NaN/infinite values or is not 3x3')
    K = K.reshape(3, 3)
    if abs(np.linalg.det(K)) < 1e-9:
        raise ValueError(f'{what}: K is singular')
    if dist is not None and not np.all(np.isfinite(np.asarray(dist, dtype=np.float64))):
        raise ValueError(f'{what}: distortion has NaN/infinite values')
    if size is not None and min(int(size[0]), int(size[1])) <= 0:
        raise ValueError(f'{what}: image size {size[0]}x{size[1]} is empty')
    return K


def rotation_angle_deg(R_a: np.ndarray, R_b: np.ndarray) -> float:
    """Angle in degrees of the relative rotation ``R_a^T R_b`` between two (3, 3) rotations."""
    cos = (np.trace(as_matrix(R_a, (3, 3), 'R_a').T @ as_matrix(R_b, (3, 3), 'R_b')) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


@dataclass(frozen=True, eq=False)
class Camera:
    """A calibrated camera at one instant.

    Attributes:
        K: (3, 3) intrinsic matrix, pixel-centre convention.
        cam_T_world: (4, 4) world-to-camera transform.
        width, height: image size in pixels.
        dist: (5,) OpenCV distortion coefficients (zeros for an ideal pinhole).
    """

    K: np.ndarray
    cam_T_world: np.ndarray
    width: int
    height: int
    dist: np.ndarray = field(default_factory=lambda: np.zeros(5))

    def __post_init__(self):
        object.__setattr__(self, 'K', as_matrix(self.K, (3, 3), 'K'))
        object.__setattr__(self, 'cam_T_world', as_matrix(self.cam_T_world, (4, 4), 'cam_T_world'))
        object.__setattr__(self, 'dist', as_matrix(np.reshape(self.dist, -1), (5,), 'dist'))
        R = self.cam_T_world[:3, :3]
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ValueError('cam_T_world must hold a proper rotation (orthonormal, det +1)')
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f'image size must be positive, got {self.width}x{self.height}')

    @classmethod
    def from_projection(cls, K, P, width: int, height: int, dist=None) -> 'Camera':
        """Build from intrinsics ``K`` (3, 3) and a projection ``P = K [R | t]`` (3, 4; world -> pixels), as
        CameraInfo carries them in this project; ``dist`` (<= 5,) is zero-padded. ValueError when K is not
        valid (:func:`check_intrinsics`) or P is not ``K [R | t]`` with a proper rotation."""
        K = check_intrinsics(K, dist, (width, height))
        P = np.asarray(P, dtype=np.float64)
        if P.size != 12 or not np.all(np.isfinite(P)):
            raise ValueError('P has NaN/infinite values or is not 3x4')
        Rt = np.linalg.solve(K, P.reshape(3, 4))
        U, _, Vt = np.linalg.svd(Rt[:, :3])  # re-orthonormalise against float noise
        R = U @ Vt
        if np.linalg.det(R) < 0 or not np.allclose(R, Rt[:, :3], atol=1e-5):
            raise ValueError('P is not K [R | t] with a proper rotation R')
        d = [float(v) for v in (dist if dist is not None else [])][:5]
        return cls(K, pose_matrix(R, Rt[:, 3]), int(width), int(height), np.array(d + [0.0] * (5 - len(d))))

    @classmethod
    def from_rvec_tvec(cls, K, rvec, tvec, width: int, height: int, dist=None) -> 'Camera':
        """Build from OpenCV's Rodrigues vector and translation (world -> camera, metres)."""
        R, _ = cv2.Rodrigues(np.asarray(rvec, dtype=np.float64).reshape(3, 1))
        return cls(K, pose_matrix(R, np.reshape(tvec, 3)), width, height, np.zeros(5) if dist is None else dist)

    @property
    def R(self) -> np.ndarray:
        """(3, 3) rotation world -> camera."""
        return self.cam_T_world[:3, :3]

    @property
    def t(self) -> np.ndarray:
        """(3,) translation world -> camera (metres)."""
        return self.cam_T_world[:3, 3]

    @property
    def rvec(self) -> np.ndarray:
        """(3,) Rodrigues vector of ``R``."""
        return cv2.Rodrigues(self.R)[0].reshape(3)

    @property
    def world_T_cam(self) -> np.ndarray:
        """(4, 4) camera-to-world transform (the camera pose)."""
        return invert_pose(self.cam_T_world)

    @property
    def center(self) -> np.ndarray:
        """(3,) camera centre in world metres."""
        return -self.R.T @ self.t

    @property
    def P(self) -> np.ndarray:
        """(3, 4) projection matrix K [R | t] (world metres -> pixels, ignoring distortion)."""
        return self.K @ self.cam_T_world[:3, :]

    @property
    def tilt_deg(self) -> float:
        """Angle of the optical axis below the horizon, in degrees (positive looks down)."""
        axis_world = self.R.T @ np.array([0.0, 0.0, 1.0])
        return float(np.degrees(np.arcsin(np.clip(-axis_world[2], -1.0, 1.0))))

    def depth(self, points_world) -> np.ndarray:
        """(N,) z of (N, 3) world points in the camera frame (negative: behind the camera)."""
        pts = as_points(points_world, 3, 'points_world')
        return pts @ self.R[2] + self.t[2]

    def project(self, points_world) -> np.ndarray:
        """Project (N, 3) world points to (N, 2) pixels, with distortion. Points behind the camera are NaN."""
        pts = as_points(points_world, 3, 'points_world')
        uv, _ = cv2.projectPoints(pts.reshape(-1, 1, 3), self.rvec, self.t, self.K, self.dist)
        uv = uv.reshape(-1, 2)
        uv[self.depth(pts) <= 0] = np.nan
        return uv

    def img_H_ground(self, plane_z: float = 0.0) -> np.ndarray:
        """(3, 3) homography: world (x, y) metres on the plane z = ``plane_z`` -> pixels (no distortion)."""
        return ground_homography(self.K, self.cam_T_world, plane_z)

    def ground_H_img(self, plane_z: float = 0.0) -> np.ndarray:
        """(3, 3) homography: pixels -> world (x, y) metres on the plane z = ``plane_z`` (no distortion)."""
        return np.linalg.inv(self.img_H_ground(plane_z))

    def undistort_pixels(self, uv) -> np.ndarray:
        """(N, 2) distorted pixels -> (N, 2) ideal pinhole pixels (identity when ``dist`` is zero)."""
        uv = as_points(uv, 2, 'uv')
        if not np.any(self.dist):
            return uv.copy()
        und = cv2.undistortPoints(uv.reshape(-1, 1, 2), self.K, self.dist, P=self.K)
        return und.reshape(-1, 2)

    def backproject_to_ground(self, uv, plane_z: float = 0.0) -> np.ndarray:
        """Intersect the rays of (N, 2) pixels with the plane z = ``plane_z``.

        Returns:
            (N, 3) world points; rows are NaN where the ray points away from the plane (above the horizon).
        """
        uv = self.undistort_pixels(uv)
        rays_cam = np.concatenate([uv, np.ones((len(uv), 1))], axis=1) @ np.linalg.inv(self.K).T
        rays_world = rays_cam @ self.R  # R^T applied to each row
        c = self.center
        with np.errstate(divide='ignore', invalid='ignore'):
            s = (plane_z - c[2]) / rays_world[:, 2]
        pts = c + s[:, None] * rays_world
        pts[~(s > 0)] = np.nan
        return pts

    def in_image(self, uv, margin: float = 0.0) -> np.ndarray:
        """(N,) bool: pixels inside the image (pixel-centre convention), shrunk by ``margin`` pixels."""
        uv = as_points(uv, 2, 'uv')
        return (
            (uv[:, 0] >= -0.5 + margin)
            & (uv[:, 0] <= self.width - 0.5 - margin)
            & (uv[:, 1] >= -0.5 + margin)
            & (uv[:, 1] <= self.height - 0.5 - margin)
        )

    def ground_to_img(self, xy, plane_z: float = 0.0) -> np.ndarray:
        """(N, 2) world metres on the plane -> (N, 2) pixels via the plane homography (no distortion)."""
        return apply_homography(self.img_H_ground(plane_z), xy)
