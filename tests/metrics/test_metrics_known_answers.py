"""Metrics on small hand-made sequences whose answers are worked out in the comments."""

import math

import numpy as np
import pytest

from matrix_core.metrics import BevPoints, detection_metrics, read_bev_points, tracking_metrics, write_bev_points


def points(rows, ids=True):
    rows = np.asarray(rows, dtype=float).reshape(-1, 4 if ids else 3)
    if ids:
        return BevPoints(rows[:, 0], rows[:, 2:4], ids=rows[:, 1])
    return BevPoints(rows[:, 0], rows[:, 1:3])


def test_detection_threshold_modp_and_frames_without_predictions():
    # frame 0: person at (0,0) detected 0.3 m away (TP, MODP term 1 - 0.3/0.5 = 0.4);
    #          person at (5,0) detected 0.6 m away -> one FN and one FP.
    # frame 1: two people, no predictions at all -> two FN.
    gt = points([[0, 0, 0, 0], [0, 1, 5, 0], [1, 0, 0, 0], [1, 1, 5, 0]])
    pred = points([[0, 0.3, 0], [0, 5.0, 0.6]], ids=False)
    m = detection_metrics(gt, pred, threshold=0.5)
    assert (m.tp, m.fp, m.fn, m.num_gt, m.num_frames) == (1, 1, 3, 4, 2)
    assert m.moda == pytest.approx(1 - 4 / 4)
    assert m.modp == pytest.approx(0.4)
    assert m.mean_error_m == pytest.approx(0.3)
    assert m.precision == pytest.approx(0.5)
    assert m.recall == pytest.approx(0.25)


def test_detection_uses_optimal_not_greedy_assignment():
    # Greedy nearest-first would pair gt A (0,0) with the prediction at (0.3,0) (0.3 m) and leave gt B
    # (0.7,0) with nothing within 0.5 m; the optimal assignment pairs A-(-0.2,0) and B-(0.3,0) (0.4 m).
    gt = points([[0, 0, 0, 0], [0, 1, 0.7, 0]])
    pred = points([[0, 0.3, 0], [0, -0.2, 0]], ids=False)
    m = detection_metrics(gt, pred)
    assert (m.tp, m.fp, m.fn) == (2, 0, 0)
    assert m.mean_error_m == pytest.approx(0.3)


def test_perfect_tracks():
    rows = [[f, i, i * 3.0 + 0.1 * f, 2.0] for f in range(10) for i in range(4)]
    gt = points(rows)
    pred = BevPoints(gt.frames, gt.xy + [0.2, 0.0], ids=gt.ids + 100)
    m = tracking_metrics(gt, pred, gate=1.0)
    assert m.mota == pytest.approx(1.0) and m.idf1 == pytest.approx(1.0)
    assert (m.id_switches, m.fragmentations, m.mostly_tracked, m.mostly_lost) == (0, 0, 4, 0)
    assert m.motp_m == pytest.approx(0.2)
    assert m.motp_percent == pytest.approx(80.0)


def test_identity_swap_counts_two_switches_and_lowers_idf1():
    # Two people 4 m apart for 6 frames; the tracker swaps their ids after frame 2.
    gt = points([[f, i, 4.0 * i, 0] for f in range(6) for i in (0, 1)])
    pred = points([[f, (i if f < 3 else 1 - i) + 10, 4.0 * i, 0] for f in range(6) for i in (0, 1)])
    m = tracking_metrics(gt, pred)
    assert m.id_switches == 2
    assert m.mota == pytest.approx(1 - 2 / 12)
    # best identity assignment keeps 3 of 6 frames per person: IDTP = 6 of 12 -> IDF1 = 0.5
    assert m.idf1 == pytest.approx(0.5)
    assert m.mostly_tracked == 2


def test_fragmentations_and_track_ratios():
    # matched pattern of the one person: T T F T F F T -> 2 fragmentations, ratio 4/7 (partially tracked)
    seen = [1, 1, 0, 1, 0, 0, 1]
    gt = points([[f, 0, 1.0, 1.0] for f in range(7)])
    pred = points([[f, 5, 1.1, 1.0] for f, s in enumerate(seen) if s])
    m = tracking_metrics(gt, pred)
    assert (m.fragmentations, m.fn, m.fp, m.id_switches) == (2, 3, 0, 0)
    assert (m.mostly_tracked, m.partially_tracked, m.mostly_lost) == (0, 1, 0)
    assert m.mota == pytest.approx(4 / 7)


def test_gate_is_respected():
    gt = points([[0, 0, 0, 0]])
    assert tracking_metrics(gt, points([[0, 1, 0.99, 0]])).matches == 1
    far = tracking_metrics(gt, points([[0, 1, 1.01, 0]]))
    assert (far.matches, far.fn, far.fp) == (0, 1, 1)
    assert math.isnan(far.motp_m)


def test_tracking_needs_ids():
    with pytest.raises(ValueError, match='ids'):
        tracking_metrics(points([[0, 0, 0, 0]]), points([[0, 0, 0]], ids=False))


def test_text_round_trip_and_errors(tmp_path):
    tracks = points([[3, 7, 1.25, -2.5], [1, 2, 0.0, 0.0]])
    write_bev_points(tmp_path / 't.txt', tracks)
    back = read_bev_points(tmp_path / 't.txt')
    assert back.has_ids and list(back.frames) == [1, 3] and list(back.ids) == [2, 7]
    np.testing.assert_allclose(back.xy, [[0, 0], [1.25, -2.5]])
    (tmp_path / 'd.txt').write_text('# frame x y score\n0 1.5 2.5 0.9\n\n1 3.0 -4.0 0.4\n')
    dets = read_bev_points(tmp_path / 'd.txt', with_ids=False)
    assert not dets.has_ids and list(dets.scores) == [0.9, 0.4]
    (tmp_path / 'bad.txt').write_text('0 1.0 nan 1\n')
    with pytest.raises(ValueError, match='bad.txt:1'):
        read_bev_points(tmp_path / 'bad.txt')
