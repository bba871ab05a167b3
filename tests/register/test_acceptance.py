"""Acceptance on the real MATRIX sample: all 8 drones, frames 0000-0004 against reference/, default settings.

Error: the registration's ground-plane homography against the one from the stored calibrations, mean over
a 0.5 m grid of ground points visible in the current frame, in full-resolution pixels.
"""

from dataclasses import replace

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register.evaluate import gt_cur_to_ref, homography_error_px
from matrix_core.register.registration import RegistrationStatus
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import RegisterSettings


def _register_all(dataset, settings, views=None, frames=None):
    """{(view, frame): (result, error_px or None)} with one registrar per view."""
    out = {}
    for view in views or dataset.views:
        ref = dataset.reference_camera(view)
        registrar = Registrar(settings, dataset.reference_image(view), ref, dataset.area, f'{view}/reference')
        for frame in frames or dataset.frames:
            r = registrar.register(dataset.load_image(view, frame), frame)
            err = (
                homography_error_px(r.ref_H_img, dataset.camera(view, frame), ref, dataset.area, settings.exclude_boxes)
                if r.ok
                else None
            )
            out[view, frame] = (r, err)
    return out


@pytest.mark.slow
def test_default_backend_meets_the_acceptance_on_the_real_sample(matrix_sample):
    cv2.setNumThreads(1)
    dataset = MatrixDataset(matrix_sample)
    settings = RegisterSettings()
    results = _register_all(dataset, settings)
    assert len(results) == 40
    failed = {k: r.message for k, (r, _) in results.items() if not r.ok}
    assert not failed, f'failed pairs: {failed}'
    errors = np.array([e for _, e in results.values()])
    assert np.median(errors) <= 0.5, f'median error {np.median(errors):.2f} px'
    assert errors.max() <= 3.0, f'worst error {errors.max():.2f} px'
    for (view, frame), (r, _) in results.items():
        assert r.backend == 'sift' and r.reference_id == f'{view}/reference'
        assert r.confidence == pytest.approx(r.inliers / r.matches)
        assert r.inliers >= settings.min_inliers and np.isfinite(r.inlier_error_px)
        # ground_H_img composes ref_H_img with the reference's ground homography.
        ref = dataset.reference_camera(view)
        np.testing.assert_allclose(
            r.ground_H_img / r.ground_H_img[2, 2],
            (ref.ground_H_img() @ r.ref_H_img) / (ref.ground_H_img() @ r.ref_H_img)[2, 2],
            rtol=1e-9,
            atol=1e-12,
        )


def test_error_metric_is_zero_for_the_truth_and_grows_with_a_shift(matrix_sample):
    dataset = MatrixDataset(matrix_sample)
    cur, ref = dataset.camera('D5', 2), dataset.reference_camera('D5')
    H = gt_cur_to_ref(cur, ref)
    assert homography_error_px(H, cur, ref, dataset.area) < 1e-6
    shift = np.array([[1, 0, 3.0], [0, 1, 4.0], [0, 0, 1]])
    assert homography_error_px(shift @ H, cur, ref, dataset.area) == pytest.approx(5.0)


def test_rekeying_chains_through_a_key_frame_and_stays_accurate(matrix_sample):
    """Force re-keying after every frame: later frames register to a key frame, chained to the reference."""
    cv2.setNumThreads(1)
    dataset = MatrixDataset(matrix_sample)
    settings = RegisterSettings(rekey_after=1, rekey_confidence=1.01, good_confidence=0.0, retry_reference_every=0)
    results = _register_all(dataset, settings, views=['D2'], frames=[0, 2, 4])
    (r0, e0), (r2, e2), (r4, e4) = (results['D2', f] for f in (0, 2, 4))
    assert r0.reference_id == 'D2/reference' and 're-keyed' in r0.message and 'frame 0' in r0.message
    assert r2.reference_id == 'D2/reference<-key:0' and 're-keyed' in r2.message
    assert r4.reference_id == 'D2/reference<-key:2'
    assert all(r.ok for r in (r0, r2, r4))
    assert max(e0, e2, e4) < 1.5, (e0, e2, e4)


def test_an_image_without_features_fails_and_publishes_no_homography(matrix_sample):
    dataset = MatrixDataset(matrix_sample)
    settings = RegisterSettings()
    ref = dataset.reference_camera('D1')
    registrar = Registrar(settings, dataset.reference_image('D1'), ref, dataset.area)
    blank = np.full((1080, 1920, 3), 128, np.uint8)
    r = registrar.register(blank, 0)
    assert r.status == RegistrationStatus.FAILED and r.ref_H_img is None and r.ground_H_img is None
    assert r.matches == 0 and r.confidence == 0.0 and r.message
    small = registrar.register(blank[:540, :960], 1)
    assert small.status == RegistrationStatus.FAILED and '960x540' in small.message
    # The registrar goes on working after failures.
    assert registrar.register(dataset.load_image('D1', 0), 2).ok


def test_rekeyed_registrar_returns_to_the_original_reference(matrix_sample):
    """Forced re-keying on frame 0, then: the reference is retried every 2 frames and takes over again when it
    registers well; a retry that is not good enough keeps the key frame; a weak chained frame retries at once."""
    cv2.setNumThreads(1)
    dataset = MatrixDataset(matrix_sample)
    ref = dataset.reference_camera('D2')
    settings = RegisterSettings(rekey_after=1, rekey_confidence=1.01, good_confidence=0.0, retry_reference_every=2)
    registrar = Registrar(settings, dataset.reference_image('D2'), ref, dataset.area, 'D2/reference')

    def register(frame):
        r = registrar.register(dataset.load_image('D2', frame), frame)
        assert r.ok, r.message
        assert (
            homography_error_px(r.ref_H_img, dataset.camera('D2', frame), ref, dataset.area, settings.exclude_boxes)
            < 1.5
        )
        return r

    assert 're-keyed' in register(0).message  # every frame is weak (rekey_confidence > 1)
    registrar.settings = replace(settings, rekey_confidence=0.1)  # from now on frames are strong
    for frame in (1, 2):  # 0 and 1 frames done on the key: no retry
        r = register(frame)
        assert r.reference_id == 'D2/reference<-key:0' and 'reference' not in r.message
    # After 2 frames on the key the retry is due, but a confidence above 1 is never good enough -> stays.
    registrar.settings = replace(settings, rekey_confidence=0.1, good_confidence=1.01)
    r3 = register(3)
    assert r3.reference_id == 'D2/reference<-key:0' and 'reference retried, stays on key:0' in r3.message
    registrar.settings = replace(settings, rekey_confidence=0.1)
    assert register(4).reference_id == 'D2/reference<-key:0'  # 3 frames done: not due
    r = register(1)  # 4 frames done: due and good -> back on the reference
    assert r.reference_id == 'D2/reference' and 'back on the reference (retried after 4 frames on key:0)' in r.message
    assert registrar.key is None
    # A weak chained frame tries the reference at once (not waiting for the period).
    registrar.settings = replace(settings, retry_reference_every=100)
    assert 're-keyed' in register(0).message
    r = register(1)
    assert r.reference_id == 'D2/reference' and 'back on the reference (retried after 0 frames on key:0)' in r.message
