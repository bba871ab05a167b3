"""The live view's geometry: frustums through the image corners, outlines, trails that follow the tracks."""

import numpy as np
import pytest

from matrix_core.datasets import MatrixDataset
from matrix_core.live_scene import LiveSceneSettings, Trails, area_outline, frustum_corners, frustum_segments


def test_frustum_corners_project_to_the_image_corners(matrix_sample):
    cam = MatrixDataset(matrix_sample).camera('D4', 0)
    corners = frustum_corners(cam.K, cam.width, cam.height, 3.0)
    assert np.allclose(corners[:, 2], 3.0)
    uv = corners @ cam.K.T
    uv = uv[:, :2] / uv[:, 2:]
    w, h = cam.width - 0.5, cam.height - 0.5
    np.testing.assert_allclose(uv, [[-0.5, -0.5], [w, -0.5], [w, h], [-0.5, h]], atol=1e-9)
    segments = frustum_segments(cam.K, cam.width, cam.height, 3.0)
    assert segments.shape == (16, 3) and np.all(segments[0:8:2] == 0)  # four edges from the apex


def test_area_outline_is_closed_on_the_ground():
    outline = area_outline((0.0, -30.0, 30.0, 0.0))
    assert np.array_equal(outline[0], outline[-1]) and np.all(outline[:, 2] == 0)
    assert {tuple(p[:2]) for p in outline} == {(0.0, -30.0), (30.0, -30.0), (30.0, 0.0), (0.0, 0.0)}


def test_trails_keep_the_last_positions_of_present_tracks():
    trails = Trails(frames=3)
    for i in range(5):
        out = trails.update([(1, (float(i), 0.0)), *([(2, (0.0, float(i)))] if i < 2 else [])])
    assert out[1].tolist() == [[2.0, 0.0], [3.0, 0.0], [4.0, 0.0]] and 2 not in out
    assert trails.update([(2, (9.0, 9.0))])[2].tolist() == [[9.0, 9.0]]  # track 2 came back: a new trail
    assert Trails(frames=0).update([(1, (0.0, 0.0))]) == {}


def test_settings_name_what_is_wrong():
    with pytest.raises(ValueError, match='area'):
        LiveSceneSettings(area=[0.0, 0.0, -1.0, 1.0])
    with pytest.raises(ValueError, match='groups of 5'):
        LiveSceneSettings(obstacle_boxes=[1.0, 2.0])
    with pytest.raises(ValueError, match='frustum_depth_m'):
        LiveSceneSettings(frustum_depth_m=0.0)
