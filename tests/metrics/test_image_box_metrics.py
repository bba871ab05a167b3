"""2D metrics (IoU >= 0.5, CLEAR MOT / IDF1 over drones) against a small hand-counted case."""

import numpy as np
import pytest

from matrix_core.metrics.image_boxes import (
    FrameBoxes,
    image_metrics,
    iou_matrix,
    per_view_metrics,
    read_mot_boxes,
    write_mot_boxes,
)

A, B, C = [0, 0, 10, 10], [100, 0, 110, 10], [200, 0, 210, 10]


def test_iou():
    np.testing.assert_allclose(iou_matrix([A], [[0, 0, 10, 5], [5, 0, 15, 10], B]), [[0.5, 1 / 3, 0.0]])


def test_known_case_over_two_drones():
    # gt: persons 1 (box A) and 2 (box B) in D1 at frames 0 and 1, person 1 in D2 at frame 0.
    gt = FrameBoxes([0, 0, 1, 1, 0], ['D1', 'D1', 'D1', 'D1', 'D2'], [1, 2, 1, 2, 1], [A, B, A, B, A])
    # pred: track 7 = person 1 everywhere; frame 1 D1 misses person 2 and has a false box at C;
    # D2 frame 0 sees person 1 as track 9 (a different identity in another drone: a switch overall).
    pred = FrameBoxes(
        [0, 0, 1, 1, 0], ['D1', 'D1', 'D1', 'D1', 'D2'], [7, 8, 7, 5, 9], [A, [101, 0, 111, 10], A, C, [1, 0, 11, 10]]
    )
    m = per_view_metrics(gt, pred)
    d1, d2, total = m['D1'], m['D2'], m['all']
    assert (d1.num_gt, d1.fp, d1.fn, d1.id_switches) == (4, 1, 1, 0)
    assert d1.precision == pytest.approx(3 / 4) and d1.recall == pytest.approx(3 / 4)
    assert d1.mota == pytest.approx(1 - 2 / 4)
    assert d2.mota == pytest.approx(1.0) and d2.idf1 == pytest.approx(1.0)
    # steps (0, D1), (0, D2), (1, D1): person 1 is 7, then 9 (switch), then 7 again (switch)
    assert (total.fp, total.fn, total.id_switches) == (1, 1, 2)
    assert total.mota == pytest.approx(1 - 4 / 5)
    # IDF1: best identity pairs 1-7 (2 boxes; 1-9 has 1), 2-8 (1) -> IDTP 3 of 5 gt and 5 pred boxes
    assert total.idf1 == pytest.approx(2 * 3 / 10)
    assert image_metrics(gt, gt).mota == 1.0


def test_mot_text_round_trip(tmp_path):
    boxes = FrameBoxes([3, 1], ['D2', 'D1'], [5, 6], [[1.5, 2, 11, 22], [0, 0, 5, 5]], [0.5, 0.25])
    write_mot_boxes(tmp_path / 'b.txt', boxes)
    assert (tmp_path / 'b.txt').read_text().splitlines()[0] == '1,6,0.00,0.00,5.00,5.00,0.2500,D1'
    back = read_mot_boxes(tmp_path / 'b.txt')
    np.testing.assert_allclose(back.boxes, [[0, 0, 5, 5], [1.5, 2, 11, 22]])
    assert back.views.tolist() == ['D1', 'D2'] and back.ids.tolist() == [6, 5]


def test_rows_by_frame_keys_each_group_by_its_own_frame():
    from matrix_core.metrics import BevPoints

    groups = BevPoints([1, 0, 1, 2], np.zeros((4, 2))).by_frame()
    assert {f: g.tolist() for f, g in groups.items()} == {0: [1], 1: [0, 2], 2: [3]}
