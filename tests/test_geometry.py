"""Camera model, homographies and BEV grid: shapes, directions and consistency."""

import numpy as np
import pytest

from matrix_core.geometry import BevGrid, Camera, apply_homography
from matrix_core.geometry.camera import invert_pose, pose_matrix, rotation_angle_deg
from matrix_core.geometry.homography import normalized


@pytest.fixture
def cam(matrix_sample):
    from matrix_core.datasets import MatrixDataset

    return MatrixDataset(matrix_sample).camera('D4', 2)


def test_projection_homography_and_backprojection_agree(cam):
    rng = np.random.default_rng(0)
    ground = np.column_stack([rng.uniform(5, 25, 50), rng.uniform(-25, -5, 50), np.zeros(50)])
    ideal = Camera(cam.K, cam.cam_T_world, cam.width, cam.height)  # no distortion
    uv = ideal.project(ground)
    np.testing.assert_allclose(apply_homography(ideal.img_H_ground(), ground[:, :2]), uv, atol=1e-6)
    np.testing.assert_allclose(ideal.backproject_to_ground(uv), ground, atol=1e-6)
    np.testing.assert_allclose(apply_homography(ideal.ground_H_img(), uv), ground[:, :2], atol=1e-6)
    # a raised plane: boards lie at z = 0.1 m
    raised = ground + [0, 0, 0.1]
    np.testing.assert_allclose(
        apply_homography(ideal.img_H_ground(0.1), raised[:, :2]), ideal.project(raised), atol=1e-6
    )
    # with the real (tiny) distortion back-projection still inverts projection
    np.testing.assert_allclose(cam.backproject_to_ground(cam.project(ground)), ground, atol=1e-3)


def test_points_behind_or_above_horizon_are_nan(cam):
    behind = cam.center + 5 * (cam.R.T @ np.array([0, 0, -1.0]))
    assert np.isnan(cam.project(behind[None])).all()
    sky = np.array([[cam.width / 2, -2000.0]])  # far above the image: ray never meets the ground
    assert np.isnan(cam.backproject_to_ground(sky)).all()


def test_pose_helpers(cam):
    np.testing.assert_allclose(invert_pose(cam.world_T_cam), cam.cam_T_world, atol=1e-12)
    np.testing.assert_allclose(cam.world_T_cam[:3, 3], cam.center)
    assert rotation_angle_deg(cam.R, cam.R) == pytest.approx(0.0, abs=1e-4)
    Rz = pose_matrix(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]), np.zeros(3))[:3, :3]
    assert rotation_angle_deg(np.eye(3), Rz) == pytest.approx(90.0)


def test_shape_and_validity_checks(cam):
    with pytest.raises(ValueError, match=r'shape \(N, 3\)'):
        cam.project(np.zeros((4, 2)))
    with pytest.raises(ValueError, match='NaN'):
        apply_homography(np.full((3, 3), np.nan), [[0, 0]])
    with pytest.raises(ValueError, match='proper rotation'):
        Camera(cam.K, pose_matrix(np.diag([1.0, -1.0, 1.0]), np.zeros(3)), 10, 10)
    with pytest.raises(ValueError, match='cannot be normalised'):
        normalized(np.array([[1.0, 0, 0], [0, 1, 0], [1, 0, 0]]))


def test_bev_grid_cells_and_homography():
    grid = BevGrid(0.0, -30.0, 30.0, 0.0, cell=0.5)
    assert grid.shape == (60, 60)
    xy = np.array([[0.25, -29.75], [29.9, -0.1]])
    np.testing.assert_allclose(grid.world_to_cell(xy), [[0, 0], [59.3, 59.3]], atol=1e-9)
    np.testing.assert_allclose(grid.cell_to_world(grid.world_to_cell(xy)), xy)
    np.testing.assert_allclose(
        apply_homography(grid.ground_H_grid, [[0, 0], [59, 59]]), [[0.25, -29.75], [29.75, -0.25]]
    )
    assert grid.contains([[1, -1], [31, -1]]).tolist() == [True, False]
    with pytest.raises(ValueError):
        BevGrid(0, 0, 0, 1)


def test_quaternions_match_scipy_both_ways():
    """geometry.quaternion (numpy, ROS order x y z w) agrees with scipy's Rotation, also near 180 degrees
    where the trace is about -1 and the other branches of Shepperd's method are taken."""
    from scipy.spatial.transform import Rotation

    from matrix_core.geometry.quaternion import matrix_from_quaternion, quaternion_from_matrix

    rotations = Rotation.random(200, random_state=3)
    flips = Rotation.from_rotvec(np.pi * np.eye(3) * (1 - 1e-9))  # 180 deg about each axis
    for r in [*rotations, *flips, Rotation.identity()]:
        q = quaternion_from_matrix(r.as_matrix())
        expected = r.as_quat()
        expected = -expected if expected[3] < 0 else expected
        np.testing.assert_allclose(q, expected, atol=1e-9)
        assert q[3] >= 0
        np.testing.assert_allclose(matrix_from_quaternion(2.0 * r.as_quat()), r.as_matrix(), atol=1e-12)
    with pytest.raises(ValueError, match='quaternion'):
        matrix_from_quaternion([0, 0, 0, 0])
