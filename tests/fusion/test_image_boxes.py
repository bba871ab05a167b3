"""Image boxes of fused tracks: projection, visibility and occlusion against hand-computed cases."""

import numpy as np
import pytest

from matrix_core.fusion.image_boxes import ImageBoxSettings, covered_fraction, image_boxes, implied_view_camera
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.homography import implied_camera

K = np.array([[1000.0, 0, 960], [0, 1000.0, 540], [0, 0, 1]])
# Camera 1 m above the origin looking along world +x, level: cam x = -world y, cam y = -world z, cam z = world x.
R = np.array([[0.0, -1, 0], [0, 0, -1], [1, 0, 0]])
CAMERA = Camera(K, pose_matrix(R, -R @ np.array([0.0, 0, 1])), 1920, 1080)
NO_OBSTACLES = ImageBoxSettings(obstacle_boxes=[])


def test_projection_of_a_known_point():
    # (10, -1, 0): 10 m ahead, 1 m right, 1 m below the camera -> (960 + 100, 540 + 100)
    np.testing.assert_allclose(CAMERA.project([[10.0, -1.0, 0.0]]), [[1060.0, 640.0]], atol=1e-9)


def test_box_of_a_person_ahead_by_hand():
    (b,) = image_boxes(CAMERA, [7], [[10.0, 0.0]], [0.9], NO_OBSTACLES)
    # u = 960 - 1000 y / x at the circle's sides (y = +-0.25, x = 10); v = 540 + 1000 (1 - z) / x: the top at
    # the near edge x = 9.75 of the head circle (z = 1.75), the bottom at the foot point (10, 0, 0)
    np.testing.assert_allclose(b.box, [935.0, 540 - 750 / 9.75, 985.0, 640.0], atol=1e-6)
    # bottom_at_foot off: the bottom of the outline, the near edge of the foot circle
    (b,) = image_boxes(CAMERA, [7], [[10.0, 0.0]], [0.9], ImageBoxSettings(obstacle_boxes=[], bottom_at_foot=False))
    np.testing.assert_allclose(b.box, [935.0, 540 - 750 / 9.75, 985.0, 540 + 1000 / 9.75], atol=1e-6)
    assert (b.track_id, b.score, b.occluded) == (7, 0.9, False)
    assert b.distance_m == pytest.approx(np.hypot(10.0, 1.0))


def test_a_person_behind_the_block_is_not_visible():
    block = ImageBoxSettings(obstacle_boxes=[4.0, -1.0, 6.0, 1.0, 3.0])
    found = image_boxes(CAMERA, [1, 2], [[10.0, 0.0], [10.0, 3.0]], [1.0, 1.0], block)
    assert [b.track_id for b in found] == [2]  # (10, 3) is beside the block, (10, 0) behind it


def test_outside_the_image_or_behind_the_camera_is_not_reported():
    # (10, 20): 2000 px left of the image; (-5, 0): behind the camera; (10, 9.84): 3 % of its box in the image
    found = image_boxes(
        CAMERA, [1, 2, 3, 4], [[10.0, 20.0], [-5.0, 0.0], [10.0, 9.84], [10.0, 0.0]], [1.0] * 4, NO_OBSTACLES
    )
    assert [b.track_id for b in found] == [4]
    for b in image_boxes(CAMERA, [5], [[10.0, 9.5]], [1.0], NO_OBSTACLES):  # mostly in: reported, clipped
        assert b.box[0] == -0.5


def test_a_person_hidden_by_a_nearer_one_is_marked_occluded():
    near, far = image_boxes(CAMERA, [1, 2], [[20.0, 0.0], [10.0, 0.0]], [1.0, 1.0], NO_OBSTACLES)
    assert (near.track_id, near.occluded, far.track_id, far.occluded) == (2, False, 1, True)


def test_occlusion_in_a_crowd_is_that_of_the_exact_union():
    # image_boxes computes the union only for boxes whose overlaps with nearer ones add up past the threshold
    rng = np.random.default_rng(3)
    flagged = 0
    for _ in range(20):
        n = int(rng.integers(5, 80))
        xy = np.column_stack([rng.uniform(5, 30, n), rng.uniform(-8, 8, n)])
        found = image_boxes(CAMERA, np.arange(n), xy, np.ones(n), NO_OBSTACLES)
        boxes = np.array([b.box for b in found])
        exact = [covered_fraction(b, boxes[:k]) > NO_OBSTACLES.person_occlusion for k, b in enumerate(boxes)]
        assert [b.occluded for b in found] == exact
        flagged += sum(exact)
    assert flagged > 20  # the crowds do hide people


def test_covered_fraction_of_the_union():
    assert covered_fraction(np.array([0, 0, 10, 10.0]), [[0, 0, 5, 10], [3, 0, 8, 5]]) == pytest.approx(0.65)


def test_the_camera_implied_by_a_ground_homography_gives_the_same_boxes():
    implied = implied_view_camera(implied_camera(K, CAMERA.img_H_ground()), (1920, 1080))
    (a,), (b,) = (image_boxes(c, [1], [[10.0, 1.0]], [1.0], NO_OBSTACLES) for c in (CAMERA, implied))
    np.testing.assert_allclose(a.box, b.box, atol=1e-6)
