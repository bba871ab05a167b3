"""Acceptance of the MATRIX data layer on the real sample (issue: workspace / data layer)."""

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.geometry.homography import apply_homography

FRAMES = range(5)


@pytest.fixture(scope='module')
def ds(matrix_sample):
    return MatrixDataset(matrix_sample)


def _visible_boxes(ds):
    for frame in FRAMES:
        positions = ds.pedestrian_positions(frame)
        for person in ds.annotations(frame):
            for view, box in person.boxes.items():
                yield frame, view, person, box, positions[person.person_id]


def test_structure(ds):
    assert ds.views == tuple(f'D{i}' for i in range(1, 9))
    assert ds.frames == (0, 1, 2, 3, 4)
    assert ds.image_size == (1920, 1080)
    assert len(ds.trajectory_frames) == 500
    assert len(ds.annotations(0)) == 40


def test_foot_points_project_to_box_bottom_centres(ds):
    dx, dy = [], []
    for frame, view, person, box, _ in _visible_boxes(ds):
        uv = ds.camera(view, frame).project(np.r_[person.world_xy, 0.0])[0]
        d = uv - box.bottom_center
        dx.append(abs(d[0]))
        dy.append(abs(d[1]))
    assert len(dx) == 1280
    assert np.median(dy) <= 2.0, np.median(dy)
    assert np.median(dx) <= 6.0, np.median(dx)


def test_box_bottoms_map_to_trajectory_positions_through_inverse_homography(ds):
    errors = []
    for frame, view, _, box, xyz in _visible_boxes(ds):
        ground = apply_homography(ds.camera(view, frame).ground_H_img(), box.bottom_center)[0]
        errors.append(np.linalg.norm(ground - xyz[:2]))
    assert np.median(errors) <= 0.15, np.median(errors)


def test_pnp_on_plane_markers_reproduces_stored_extrinsics(ds):
    for frame in range(1, 5):
        for view in ds.views:
            pc = ds.plane_correspondences(view, frame)
            assert pc is not None and len(pc.marker_ids) >= 80
            cam = ds.camera(view, frame)
            ok, rvec, tvec = cv2.solvePnP(pc.world_xyz, pc.image_uv, cam.K, cam.dist, flags=cv2.SOLVEPNP_ITERATIVE)
            assert ok
            R = cv2.Rodrigues(rvec)[0]
            assert rotation_angle_deg(R, cam.R) <= 0.01
            assert np.linalg.norm(-R.T @ tvec.ravel() - cam.center) <= 0.01


def test_bogus_frame_zero_planes_are_refused(ds):
    assert ds.plane_correspondences('D1', 0) is None


def test_world_frame_is_right_handed_and_cameras_look_down(ds):
    for view in ds.views:
        cam = ds.camera(view, 1)
        assert np.linalg.det(cam.R) == pytest.approx(1.0)
        assert 11.0 < cam.center[2] < 13.5
        assert cam.tilt_deg > 0
        # The middle of the square projects inside every image.
        centre = np.array([[15.0, ds.area[1] + 15.0, 0.0]])
        assert cam.in_image(cam.project(centre))[0]


def test_reference_cameras_on_the_ring(ds):
    x0, y0, x1, y1 = ds.area
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for view in ds.views:
        cam = ds.reference_camera(view)
        assert cam.center[2] == pytest.approx(12.29, abs=0.05)
        assert 22.0 < np.linalg.norm(cam.center[:2] - centre) < 33.0


def test_line_of_sight_equals_annotated_views(ds):
    for frame in range(2):
        persons = ds.annotations(frame)
        for view in ds.views:
            annotated = {p.person_id for p in persons if view in p.boxes}
            assert annotated == ds.line_of_sight(view, frame)
