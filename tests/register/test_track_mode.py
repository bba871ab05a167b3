"""Registration mode ``track`` on the real MATRIX sample: frames between anchors are registered from the
previous frame by optical flow, refined against the anchor, and stay as accurate as the per-frame
registration; anchors come when due, on the first frame and after a frame the chain cannot follow.

Error: against the stored calibrations (``homography_error_px``), full-resolution pixels. The 100-frame
simulated figures: ``python scripts/bench_register.py --simulated --mode track`` (docs/registration.md).
"""

from dataclasses import replace

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.flow_tracking import FlowTracker
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import MATRIX_BLOCK, RegisterSettings

TRACK = RegisterSettings(mode='track')
# A frame without a registered previous one: a feature anchor, or an anchor by flow to the reference (refined at
# 960x540, D6's frames 0 and 3 hold by flow).
NO_PREVIOUS = ('anchor: no registered previous frame', 'anchor by flow to the reference: no registered previous frame')


@pytest.fixture(scope='module')
def dataset(matrix_sample):
    cv2.setNumThreads(1)
    return MatrixDataset(matrix_sample)


def _run(dataset, settings, view, images):
    """[(Registration, error px or None)] of ``images`` [(frame id, image)] through one registrar of ``view``."""
    ref = dataset.reference_camera(view)
    registrar = Registrar(settings, dataset.reference_image(view), ref, dataset.area, f'{view}/reference')
    out = []
    for frame, image in images:
        r = registrar.register(image, frame)
        error = (
            homography_error_px(r.ref_H_img, dataset.camera(view, frame), ref, dataset.area, MATRIX_BLOCK)
            if r.ok
            else None
        )
        out.append((r, error))
    return out


def _frames(dataset, view, frames):
    return [(f, dataset.load_image(view, f)) for f in frames]


def test_tracked_frames_chain_to_the_anchor_and_stay_accurate(dataset):
    results = _run(dataset, TRACK, 'D6', _frames(dataset, 'D6', dataset.frames))
    (anchor, e0), tracked = results[0], results[1:]
    assert anchor.ok and anchor.reference_id == 'D6/reference'
    assert anchor.message.startswith(NO_PREVIOUS), anchor.message
    for k, (r, error) in enumerate(tracked, 1):
        assert r.ok and r.reference_id == 'D6/reference<-track:0', (k, r.message)
        assert r.message == f'tracked: {k} frame(s) after its anchor'
        assert r.inliers >= TRACK.track_min_inliers and r.confidence == pytest.approx(r.inliers / r.matches)
        assert error < 1.0, f'frame {k}: {error:.2f} px'
        # The calibration's guide: the camera the chained homography implies, computed by the gate.
        assert r.implied is not None and abs(r.implied.center[2] - dataset.camera('D6', k).center[2]) < 0.5
    errors = [e0] + [e for _, e in tracked]
    assert np.median(errors) <= 0.5, errors


def test_a_frame_from_another_drone_doubts_the_chain_and_the_next_frame_anchors(dataset):
    images = _frames(dataset, 'D6', [0, 1]) + [(2, dataset.load_image('D5', 2))] + _frames(dataset, 'D6', [3, 4])
    (r0, _), (r1, _), (swapped, _), (r3, e3), (r4, e4) = _run(dataset, TRACK, 'D6', images)
    assert r1.message.startswith('tracked')
    assert swapped.message.startswith('anchor: chain doubted'), swapped.message
    assert not swapped.ok  # D5's view does not register to D6's reference either
    assert r3.ok and r3.message.startswith(NO_PREVIOUS), r3.message
    assert r3.reference_id == 'D6/reference'
    assert r4.ok and r4.reference_id == 'D6/reference<-track:3' and r4.message.startswith('tracked')
    assert max(e3, e4) < 1.0


def test_reanchor_every_forces_full_registrations(dataset):
    images = _frames(dataset, 'D6', dataset.frames)
    features = replace(TRACK, anchor_by_flow=False)  # anchors by features only (by flow: the next tests)
    every2 = _run(dataset, replace(features, reanchor_every=2), 'D6', images)
    assert [r.message.split(':')[0] for r, _ in every2] == ['anchor', 'tracked', 'anchor', 'tracked', 'anchor']
    assert every2[2][0].message.startswith('anchor: due (every 2 frames)')
    # Every frame an anchor: the per-frame registration's homographies, unchanged.
    every1 = _run(dataset, replace(features, reanchor_every=1), 'D6', images[:2])
    per_frame = _run(dataset, RegisterSettings(), 'D6', images[:2])
    for (a, _), (b, _) in zip(every1, per_frame):
        assert a.ok and b.ok and b.message == '' and a.reference_id == b.reference_id == 'D6/reference'
        np.testing.assert_array_equal(a.ref_H_img, b.ref_H_img)


def test_mode_is_checked():
    with pytest.raises(ValueError, match="mode must be reference or track, got 'flow'"):
        RegisterSettings(mode='flow')
    with pytest.raises(ValueError, match='reanchor_every'):
        RegisterSettings(reanchor_every=-1)


def _moved_reference(dataset, view, moves):
    """[(frame id, image)]: the reference image of ``view`` moved by each (dx, dy, degrees) about its centre (a
    drone drifting over a static scene), and [(3, 3) ref_H_img] their exact registrations."""
    image = dataset.reference_image(view)
    h, w = image.shape[:2]
    frames, truths = [], []
    for k, (dx, dy, degrees) in enumerate(moves):
        img_H_ref = np.vstack([cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), degrees, 1.0), [0, 0, 1]])
        img_H_ref[:2, 2] += (dx, dy)
        frames.append((k, cv2.warpPerspective(image, img_H_ref, (w, h), flags=cv2.INTER_LINEAR)))
        truths.append(np.linalg.inv(img_H_ref))
    return frames, truths


def _max_difference_px(H, G, width=1920, height=1080):
    """Largest distance between where ``H`` and ``G`` map the central half of a full-resolution image."""
    xs, ys = np.meshgrid(np.linspace(width / 4, 3 * width / 4, 9), np.linspace(height / 4, 3 * height / 4, 9))
    points = np.stack([xs.ravel(), ys.ravel()], axis=1).reshape(-1, 1, 2)
    return float(np.abs(cv2.perspectiveTransform(points, H) - cv2.perspectiveTransform(points, G)).max())


def test_anchors_by_flow_register_to_the_reference_itself(dataset):
    frames, truths = _moved_reference(dataset, 'D6', [(8, -5, 0.2), (14, -3, 0.3), (22, 2, 0.5)])
    results = _run(dataset, replace(TRACK, reanchor_every=2), 'D6', frames)
    (first, _), (second, _), (due, _) = results
    assert first.message == 'anchor by flow to the reference: no registered previous frame', first.message
    assert second.message == 'tracked: 1 frame(s) after its anchor'
    assert second.reference_id == 'D6/reference<-track:0'
    assert due.message == 'anchor by flow to the reference: due (every 2 frames)', due.message
    for (r, _), truth in zip(results, truths):
        assert r.ok and r.inliers >= TRACK.track_min_inliers
        assert _max_difference_px(r.ref_H_img, truth) < 0.5, r.message
    assert first.reference_id == due.reference_id == 'D6/reference'
    # Off: the same frames anchor by features.
    off = _run(dataset, replace(TRACK, reanchor_every=2, anchor_by_flow=False), 'D6', frames)
    assert [r.message for r, _ in off][::2] == ['anchor: no registered previous frame', 'anchor: due (every 2 frames)']


def test_an_anchor_by_flow_that_does_not_hold_falls_back_to_features(dataset):
    """The real sample's references were filmed at another time: the flow to them does not hold, features do;
    after two such tries in a row, only due anchors try it again."""
    images = _frames(dataset, 'D2', dataset.frames)
    results = _run(dataset, TRACK, 'D2', images)
    tried = [r.message for r, _ in results if 'by flow to the reference' in r.message]
    assert results[0][0].message.startswith('anchor: no registered previous frame; by flow to the reference: ')
    assert len(tried) == 2, [r.message for r, _ in results]
    assert all(r.ok and error < 1.0 for r, error in results)


def test_the_refinement_repeats_until_a_poor_prediction_converges(dataset, monkeypatch):
    """A flow prediction 7 px off. Refined at the flow's 480x270: one pass leaves about 0.2 px (on simulated
    complex seed 3, D2 frame 94, a worse prediction left 6.5 px), the repeated passes converge further (measured
    0.08 px). Refined at 960x540 (the default, one pyramid level), the passes end within a few hundredths of a
    pixel (measured 0.005 px; one pass 0.02, and 0.1-0.4 px from predictions 12-25 px off)."""
    from matrix_core.register import flow_tracking
    from matrix_core.register.flow_tracking import FlowStart

    (_, image), truth = [x[0] for x in _moved_reference(dataset, 'D6', [(10, 6, 0.3)])]
    ref = dataset.reference_camera('D6')
    # The "previous frame" is the reference itself, believed 7 px away from where it is.
    off = np.array([[1.0, 0, 7], [0, 1, -3], [0, 0, 1]])
    errors = {}
    for refine_scale in (TRACK.scale, TRACK.track_refine_scale):
        tracker = FlowTracker(TRACK.scale, TRACK.flow_corners, TRACK.homography_ransac_px, refine_scale=refine_scale)
        reference = tracker.anchor(
            tracker.reduce(dataset.reference_image('D6')),
            ref,
            np.eye(3),
            'D6/reference',
            500,
            dataset.area,
            0.0,
            MATRIX_BLOCK,
        )
        state = FlowStart(reference.anchor, reference.images, reference.corners, off)
        for passes in (1, flow_tracking.REFINE_PASSES):
            monkeypatch.setattr(flow_tracking, 'REFINE_PASSES', passes)
            step = tracker.step(state, tracker.reduce(image))
            errors[refine_scale, passes] = _max_difference_px(step.anchor_H_cur, truth)
    coarse, fine, repeated = TRACK.scale, TRACK.track_refine_scale, flow_tracking.REFINE_PASSES
    assert errors[coarse, repeated] < min(0.15, errors[coarse, 1] / 2), errors
    assert errors[fine, repeated] < min(0.05, errors[coarse, repeated]), errors


def test_the_flow_step_tracks_forward_only(dataset):
    """The flow step only predicts (its robust fit rejects bad corners; the refinement, checked both ways,
    decides): its Lucas-Kanade runs forward only, half its CPU time; the same positions as with the backward
    check, more corners kept."""
    from matrix_core.register import flow_tracking as ft

    tracker = FlowTracker(TRACK.scale, TRACK.flow_corners, TRACK.homography_ransac_px)
    a, b = (tracker.reduce(dataset.load_image('D6', f)).flow for f in dataset.frames[:2])
    corners = cv2.goodFeaturesToTrack(a, 500, ft.CORNER_QUALITY, ft.CORNER_MIN_DISTANCE)
    both, checked = ft._track(a, b, corners, None, ft.FLOW_WINDOW, ft.FLOW_LEVELS)
    forward, kept = ft._track(a, b, corners, None, ft.FLOW_WINDOW, ft.FLOW_LEVELS, backward=False)
    np.testing.assert_array_equal(forward, both)
    assert (kept >= checked).all() and kept.sum() > checked.sum(), (kept.sum(), checked.sum())
    assert not ft.FLOW_BACKWARD_CHECK
