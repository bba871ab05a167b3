"""Registration mode ``track`` on the real MATRIX sample: frames between anchors are registered from the
previous frame by optical flow, refined against the anchor, and stay as accurate as the per-frame
registration; anchors come when due, on the first frame and after a frame the chain cannot follow.

Error: against the stored calibrations (``homography_error_px``), full-resolution pixels. The 100-frame
simulated figures: ``python scripts/bench_register.py --simulated --mode track`` (see README).
"""

from dataclasses import replace

import cv2
import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.registrar import Registrar
from matrix_core.register.settings import MATRIX_BLOCK, RegisterSettings

TRACK = RegisterSettings(mode='track')


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
        error = homography_error_px(r.ref_H_img, dataset.camera(view, frame), ref, dataset.area,
                                    MATRIX_BLOCK) if r.ok else None
        out.append((r, error))
    return out


def _frames(dataset, view, frames):
    return [(f, dataset.load_image(view, f)) for f in frames]


def test_tracked_frames_chain_to_the_anchor_and_stay_accurate(dataset):
    results = _run(dataset, TRACK, 'D6', _frames(dataset, 'D6', dataset.frames))
    (anchor, e0), tracked = results[0], results[1:]
    assert anchor.ok and anchor.reference_id == 'D6/reference'
    assert anchor.message.startswith('anchor: no registered previous frame')
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
    assert r3.ok and r3.message.startswith('anchor: no registered previous frame'), r3.message
    assert r3.reference_id == 'D6/reference'
    assert r4.ok and r4.reference_id == 'D6/reference<-track:3' and r4.message.startswith('tracked')
    assert max(e3, e4) < 1.0


def test_reanchor_every_forces_full_registrations(dataset):
    images = _frames(dataset, 'D6', dataset.frames)
    every2 = _run(dataset, replace(TRACK, reanchor_every=2), 'D6', images)
    assert [r.message.split(':')[0] for r, _ in every2] == ['anchor', 'tracked', 'anchor', 'tracked', 'anchor']
    assert every2[2][0].message.startswith('anchor: due (every 2 frames)')
    # Every frame an anchor: the per-frame registration's homographies, unchanged.
    every1 = _run(dataset, replace(TRACK, reanchor_every=1), 'D6', images[:2])
    per_frame = _run(dataset, RegisterSettings(), 'D6', images[:2])
    for (a, _), (b, _) in zip(every1, per_frame):
        assert a.ok and b.ok and b.message == '' and a.reference_id == b.reference_id == 'D6/reference'
        np.testing.assert_array_equal(a.ref_H_img, b.ref_H_img)


def test_mode_is_checked():
    with pytest.raises(ValueError, match="mode must be reference or track, got 'flow'"):
        RegisterSettings(mode='flow')
    with pytest.raises(ValueError, match='reanchor_every'):
        RegisterSettings(reanchor_every=-1)
