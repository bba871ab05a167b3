"""Scores and picture of the graph monitor, on the real sample's calibrations."""

import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.evaluation.graph_report import (
    ground_homography_error_m,
    overview_image,
    score_view_frame,
    summary_table,
    true_references,
    write_graph_report,
)
from matrix_core.geometry.camera import Camera
from matrix_core.register.evaluate import gt_cur_to_ref
from matrix_core.register.registration import Registration, RegistrationStatus


@pytest.fixture(scope='module')
def ds(matrix_sample):
    return MatrixDataset(matrix_sample)


def _shifted(cam: Camera, dx: float) -> Camera:
    """The same camera moved dx metres along world x."""
    world_T_cam = cam.world_T_cam.copy()
    world_T_cam[0, 3] += dx
    return Camera(cam.K, np.linalg.inv(world_T_cam), cam.width, cam.height, cam.dist)


def test_perfect_estimates_score_zero_and_shifts_are_measured(ds):
    truth = ds.camera('D2', 1)
    perfect = score_view_frame('D2', 1.5, truth, ds.area, truth, RegistrationStatus.OK, 0.9, truth.ground_H_img())
    assert perfect.rot_err_deg == pytest.approx(0, abs=1e-3) and perfect.centre_err_m == pytest.approx(0, abs=1e-9)
    assert perfect.reg_ground_err_m == pytest.approx(0, abs=1e-6)
    moved = _shifted(truth, 0.3)
    # a camera moved by 0.3 m sees the ground shifted by 0.3 m: the homography error says so
    assert ground_homography_error_m(moved.ground_H_img(), truth, ds.area) == pytest.approx(0.3, abs=1e-6)
    bad = score_view_frame('D2', 1.5, truth, ds.area, moved, RegistrationStatus.FAILED, 0.1, None, 'too few inliers')
    assert bad.centre_err_m == pytest.approx(0.3) and bad.reg_ground_err_m is None
    # the registration's status and message go to their own columns (graph_scores.csv), not into a pose error
    assert perfect.reg_status == RegistrationStatus.OK and bad.reg_status == RegistrationStatus.FAILED
    assert bad.reg_message == 'too few inliers'
    unposed = score_view_frame('D2', 1.5, truth, ds.area, None, RegistrationStatus.OK, 0.9, truth.ground_H_img())
    assert unposed.rot_err_deg is None and unposed.reg_status == RegistrationStatus.OK


def test_summary_table_and_picture(ds):
    scores = [
        score_view_frame(
            v,
            1.0,
            ds.camera(v, 0),
            ds.area,
            ds.camera(v, 0),
            RegistrationStatus.OK,
            0.8,
            ds.camera(v, 0).ground_H_img(),
        )
        for v in ds.views[:3]
    ]
    scores.append(score_view_frame('D4', 1.0, ds.camera('D4', 0), ds.area))
    table = summary_table(scores, ['D1', 'D2', 'D3', 'D4'])
    assert table.splitlines()[-2].split()[:3] == ['all', '4', '3']
    assert ' D4      1     0        -' in table
    images = {v: ds.load_image(v, 0) for v in ds.views[:2]}
    cams = {v: ds.camera(v, 0) for v in ds.views[:2]}
    truth_only = overview_image(images, cams, ds.area, thumb_width=320)
    assert truth_only.shape == (180, 640, 3)
    # the projected area outline is drawn in white
    assert (truth_only == 255).all(axis=2).sum() > 500
    est = overview_image(images, cams, ds.area, cams, thumb_width=320).astype(int)
    green = (est[:, :, 1] > 180) & (est[:, :, 0] < 60) & (est[:, :, 2] < 60)
    assert green.sum() > 300  # published calibration drawn in green over the white truth


def test_registration_error_in_reference_pixels(ds, tmp_path):
    truth, ref = ds.camera('D2', 1), ds.reference_camera('D2')
    exact = gt_cur_to_ref(truth, ref)
    ground = ref.ground_H_img() @ exact
    perfect = score_view_frame(
        'D2', 1.5, truth, ds.area, truth, RegistrationStatus.OK, 0.9, ground, ref_H_img=exact, reference=ref
    )
    assert perfect.reg_ref_err_px == pytest.approx(0, abs=1e-6)
    # the homography followed by a 3-4-5 px shift in the reference image is 5 px off everywhere
    shifted = np.array([[1.0, 0.0, 3.0], [0.0, 1.0, 4.0], [0.0, 0.0, 1.0]]) @ exact
    off = score_view_frame(
        'D2', 1.5, truth, ds.area, truth, RegistrationStatus.OK, 0.9, ground, ref_H_img=shifted, reference=ref
    )
    assert off.reg_ref_err_px == pytest.approx(5.0, abs=1e-6)
    # without the reference camera, or for a failed registration, there is no pixel figure
    assert score_view_frame('D2', 1.5, truth, ds.area, truth, RegistrationStatus.OK, 0.9, ground).reg_ref_err_px is None
    failed = score_view_frame(
        'D2', 1.5, truth, ds.area, truth, RegistrationStatus.FAILED, 0.1, None, ref_H_img=shifted, reference=ref
    )
    assert failed.reg_ref_err_px is None
    # the report's table and CSV carry it, for the views whose reference it was given
    registration = Registration(RegistrationStatus.OK, ref_H_img=shifted, ground_H_img=ground, confidence=0.9)
    scored = write_graph_report(
        tmp_path, ['D2'], ds.area, {('D2', 1.5): truth}, {}, {('D2', 1.5): registration}, {}, {'D2': ref}
    )
    assert scored == 1
    table = (tmp_path / 'graph_summary.txt').read_text().splitlines()
    assert table[0].split()[-1] == 'ref_px' and table[2].split()[-1] == '5.000'
    assert 'reg_ref_err_px' in (tmp_path / 'graph_scores.csv').read_text().splitlines()[0]


def test_a_reference_frame_in_the_recording_is_scored_by_its_true_camera(ds):
    estimated_ref, true_ref = _shifted(ds.reference_camera('D2'), 0.2), ds.reference_camera('D2')
    truth = {('D2', 4.5): true_ref, ('D2', 5.0): ds.camera('D2', 1), ('D3', 4.5): ds.camera('D3', 1)}
    references = {'D2': estimated_ref, 'D3': ds.reference_camera('D3'), 'D4': ds.reference_camera('D4')}
    # D2's reference frame (4.5 s, the stamp as a float sum) is in the recording; D4's is not; D3 names none
    cameras, true_views = true_references(references, {'D2': 4.5 + 3e-9, 'D4': 9.0}, truth)
    assert true_views == ['D2']
    assert cameras['D2'] is true_ref
    assert cameras['D3'] is references['D3'] and cameras['D4'] is references['D4']
    # the registration exactly right for the true reference is 0 px off against it, not against the estimate
    cur = ds.camera('D2', 1)
    exact = gt_cur_to_ref(cur, true_ref)
    ground = true_ref.ground_H_img() @ exact
    args = ('D2', 5.0, cur, ds.area, cur, RegistrationStatus.OK, 0.9, ground)
    against_truth = score_view_frame(*args, ref_H_img=exact, reference=cameras['D2'])
    assert against_truth.reg_ref_err_px == pytest.approx(0, abs=1e-6)
    assert score_view_frame(*args, ref_H_img=exact, reference=estimated_ref).reg_ref_err_px > 1.0


def test_summary_table_fits_long_drone_names(ds):
    truth = ds.camera('D1', 1)
    scores = [score_view_frame('north_east', 0.5, truth, ds.area, truth)]
    lines = summary_table(scores, ['north_east']).splitlines()
    assert lines[0].split()[0] == 'view' and lines[2].split()[0] == 'north_east'
    assert len(lines[0]) == len(lines[2]) == len(lines[3])
