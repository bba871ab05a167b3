"""The exact segment-box occlusion test (geometry.occlusion) on hand-built cases."""

import numpy as np
import pytest

from matrix_core.geometry.occlusion import as_boxes, segments_blocked

BOX = [0.0, 0.0, 2.0, 2.0, 10.0]  # 2 x 2 m footprint, 10 m tall


def test_segments_through_beside_over_and_under_the_box():
    origin = np.array([-5.0, 1.0, 4.0])
    targets = np.array(
        [
            [5.0, 1.0, 0.0],  # ground behind the box: blocked
            [-1.0, 1.0, 0.0],  # ground in front of it
            [5.0, 5.0, 0.0],  # passes beside it
            [5.0, 1.0, 30.0],  # passes over it
            [1.0, 1.0, 0.0],  # ground under the box: enters through its side
            [0.0, 1.0, 0.0],  # foot of the near wall: touches it only
            [2.0, 1.0, 0.0],  # foot of the far wall: crosses the box first
            [np.nan, 0.0, 0.0],
        ]
    )
    assert segments_blocked(origin, targets, BOX).tolist() == [True, False, False, False, True, False, True, False]


def test_box_behind_or_around_the_camera():
    # The box reaching behind the camera (where projected corners are meaningless) changes nothing.
    origin = np.array([1.0, -1.0, 5.0])  # beside the box, below its top
    targets = np.array([[1.0, -10.0, 0.0], [1.0, 10.0, 0.0], [1.0, 3.0, 30.0]])
    assert segments_blocked(origin, targets, BOX).tolist() == [False, True, False]


def test_several_boxes_axis_parallel_rays_and_no_box():
    boxes = BOX + [10.0, 0.0, 12.0, 2.0, 1.0]
    origin = np.array([-5.0, 1.0, 0.5])
    targets = np.array([[5.0, 1.0, 0.5], [20.0, 1.0, 0.5], [-5.0, 1.0, 0.0]])
    assert segments_blocked(origin, targets, boxes).tolist() == [True, True, False]
    assert segments_blocked(origin, targets, []).tolist() == [False, False, False]
    assert as_boxes(boxes).shape == (2, 5)
    with pytest.raises(ValueError, match='groups of 5'):
        as_boxes([1.0, 2.0, 3.0])
