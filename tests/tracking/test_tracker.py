"""BevTracker on the real MATRIX sample trajectories (matchings/Pedestrians, 500 frames x 40 people)
turned into imperfect detections, plus small cases for birth, death and reset."""

import numpy as np
import pytest

from matrix_core.datasets import open_dataset
from matrix_core.metrics import BevPoints, tracking_metrics
from matrix_core.tracking import BevDetections, BevTracker, TrackerSettings


@pytest.fixture(scope='module')
def trajectories(matrix_sample):
    """(frames, ids, xy) of the real pedestrians (world metres), first 200 time steps."""
    ds = open_dataset(matrix_sample)
    frames, ids, xy = [], [], []
    for f in ds.trajectory_frames[:200]:
        for pid, p in ds.pedestrian_positions(f).items():
            frames.append(f)
            ids.append(pid)
            xy.append(p[:2])
    assert len(frames) == 200 * 40
    return BevPoints(frames, xy, ids=ids)


def noisy_detections(gt: BevPoints, seed: int, miss=0.1, noise=0.1, false_alarms=1.0, with_offsets=True):
    """Per frame: every person detected with prob 1 - miss, Gaussian position noise, random false alarms
    with low scores, and CenterTrack offsets (to the previous position) with noise."""
    rng = np.random.default_rng(seed)
    prev = {}
    out = []
    for f in gt.frame_numbers:
        rows = gt.at(f)
        xy, scores, offs = [], [], []
        for r in rows:
            pid, p = int(gt.ids[r]), gt.xy[r]
            if rng.random() >= miss:
                xy.append(p + rng.normal(0, noise, 2))
                scores.append(rng.uniform(0.55, 1.0))
                offs.append(prev.get(pid, p) - p + rng.normal(0, noise / 2, 2))
            prev[pid] = p
        for _ in range(rng.poisson(false_alarms)):
            xy.append(rng.uniform([0, -30], [30, 0]))
            scores.append(rng.uniform(0.2, 0.6))
            offs.append(rng.normal(0, 0.3, 2))
        out.append(
            (
                int(f),
                BevDetections(np.reshape(xy, (-1, 2)), scores, np.reshape(offs, (-1, 2)) if with_offsets else None),
            )
        )
    return out


def run(tracker, frames_dets):
    frames, ids, xy = [], [], []
    for f, dets in frames_dets:
        for t in tracker.update(dets):
            frames.append(f)
            ids.append(t.track_id)
            xy.append(t.xy)
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


@pytest.mark.parametrize('with_offsets', [True, False])
def test_tracks_real_pedestrians_through_misses(trajectories, with_offsets):
    dets = noisy_detections(trajectories, seed=1, with_offsets=with_offsets)
    tracks = run(BevTracker(), dets)
    m = tracking_metrics(trajectories, tracks, gate=1.0)
    # 10 % of detections missing: the Kalman prediction bridges the gaps, so identities survive (a miss
    # of one frame is reported at the prediction with the default report_coasting 1).
    assert m.mota > 0.85, m
    assert m.mostly_tracked >= 38, m
    if with_offsets:  # CenterTrack offsets make frame-to-frame association nearly unambiguous
        assert m.idf1 > 0.88 and m.id_switches <= 12, m
    else:  # pedestrians turn within 0.5 s; the constant-velocity model alone slips now and then
        assert m.idf1 > 0.8 and m.id_switches <= 40, m


def test_offsets_help_when_people_cross(trajectories):
    """With large detection noise the CenterTrack offsets carry identities better than the Kalman alone."""
    dets_off = noisy_detections(trajectories, seed=2, noise=0.25, miss=0.05)
    dets_no = [(f, BevDetections(d.xy, d.scores)) for f, d in dets_off]
    with_off = tracking_metrics(trajectories, run(BevTracker(), dets_off))
    without = tracking_metrics(trajectories, run(BevTracker(), dets_no))
    assert with_off.id_switches <= without.id_switches
    assert with_off.idf1 >= without.idf1 - 0.01


def single(xy, score=0.9):
    return BevDetections(np.reshape(xy, (-1, 2)), [score] * (len(np.reshape(xy, (-1, 2)))))


def test_birth_after_k_hits_and_death_after_m_misses():
    tr = BevTracker(TrackerSettings(birth_hits=3, max_misses=2, confirm_first_frame=False, report_coasting=0))
    assert tr.update(single([0, 0])) == []
    assert tr.update(single([0.5, 0])) == []
    out = tr.update(single([1.0, 0]))
    assert [o.track_id for o in out] == [1]
    assert out[0].velocity[0] > 0.5  # learned ~1 m/s along x
    # two frames missing: the track coasts (not reported) and is picked up again where it should be
    assert tr.update(single(np.zeros((0, 2)))) == [] and tr.update(single(np.zeros((0, 2)))) == []
    assert [o.track_id for o in tr.update(single([2.5, 0]))] == [1]
    # three frames missing > max_misses: deleted; the person comes back as a new, tentative track
    for _ in range(3):
        tr.update(single(np.zeros((0, 2))))
    assert tr.update(single([4.0, 0])) == []
    assert tr.update(single([4.5, 0])) == [] and [o.track_id for o in tr.update(single([5.0, 0]))] == [2]


def test_first_frame_tracks_are_confirmed_at_once_and_coasting_is_reported_only_on_request():
    tr = BevTracker(TrackerSettings(birth_hits=2, report_coasting=1))
    assert [o.track_id for o in tr.update(single([0, 0]))] == [1]  # first frame: id at once
    assert [o.track_id for o in tr.update(single([[0, 0], [5, 5]]))] == [1]  # newcomers wait birth_hits
    out = tr.update(single(np.zeros((0, 2))))  # track 1 coasts one frame
    assert [(o.track_id, o.misses) for o in out] == [(1, 1)]
    assert tr.update(single(np.zeros((0, 2)))) == []  # two misses > report_coasting
    tr.reset()
    assert [o.track_id for o in tr.update(single([0, 0]))] == [1]  # first frame again after reset()
    quiet = BevTracker(TrackerSettings(birth_hits=2, report_coasting=0))
    quiet.update(single([0, 0]))
    assert quiet.update(single(np.zeros((0, 2)))) == []  # report_coasting 0: misses are not reported


def test_low_scores_extend_but_never_start_tracks_and_reset_restarts_ids():
    tr = BevTracker(TrackerSettings(birth_hits=1, report_coasting=0))
    assert tr.update(single([0, 0], score=0.3)) == []  # weak detection: no new track
    assert [o.track_id for o in tr.update(single([0, 0]))] == [1]
    assert [o.track_id for o in tr.update(single([0.2, 0], score=0.3))] == [1]  # weak one extends it
    assert tr.update(single([9, 9], score=0.1)) == []  # below low_score: ignored
    tr.reset()
    assert tr.tracks == []
    assert [o.track_id for o in tr.update(single([5, 5]))] == [1]


def test_gate_separates_far_detections():
    tr = BevTracker(TrackerSettings(birth_hits=1, gate_m=1.0, report_coasting=0))
    first = tr.update(single([0, 0]))
    second = tr.update(single([1.5, 0]))  # 1.5 m jump > gate: a different person
    assert [o.track_id for o in first] == [1] and [o.track_id for o in second] == [2]


def test_rejects_bad_input():
    with pytest.raises(ValueError, match='NaN'):
        BevDetections([[np.nan, 0]], [0.9])
    with pytest.raises(ValueError, match='low_score'):
        TrackerSettings(low_score=0.8, high_score=0.5)


def test_a_track_reports_its_detection_of_the_frame_beside_the_filtered_position():
    tr = BevTracker(TrackerSettings(birth_hits=1, report_coasting=1))
    tr.update(single([0, 0]))
    (out,) = tr.update(single([0.6, 0.2]))
    np.testing.assert_allclose(out.detection_xy, [0.6, 0.2])  # where the person is now
    assert not np.allclose(out.xy, out.detection_xy)  # the filter lags behind
    (coasting,) = tr.update(single(np.zeros((0, 2))))
    np.testing.assert_allclose(coasting.detection_xy, coasting.xy)  # no detection: the prediction
