"""Reference features are kept only where the reference camera sees the scene ground."""

import cv2
import numpy as np

from matrix_core.datasets import MatrixDataset
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.occlusion import segments_blocked
from matrix_core.register.backend_sift import SiftBackend
from matrix_core.register.ground_mask import ground_pixels, visible_ground_grid
from matrix_core.register.reference import Reference
from matrix_core.register.settings import MATRIX_BLOCK


def test_reference_keeps_ground_features_only(matrix_sample):
    cv2.setNumThreads(1)
    dataset = MatrixDataset(matrix_sample)
    cam = dataset.reference_camera('D1')
    features = SiftBackend(0.25, 0.005).extract(dataset.reference_image('D1'), 16000)
    ref = Reference('D1/reference', cam, features, dataset.area, True, 0.0, MATRIX_BLOCK)
    assert 100 < len(ref.features) < len(features)
    ground = cam.backproject_to_ground(ref.features.xy)
    x0, y0, x1, y1 = dataset.area
    assert np.all((ground[:, 0] >= x0) & (ground[:, 0] <= x1) & (ground[:, 1] >= y0) & (ground[:, 1] <= y1))
    # None lies on the block's footprint (the block hides it).
    bx0, by0, bx1, by1, _ = MATRIX_BLOCK
    on_block = (ground[:, 0] > bx0) & (ground[:, 0] < bx1) & (ground[:, 1] > by0) & (ground[:, 1] < by1)
    assert not on_block.any()


def test_block_faces_sky_and_outside_are_not_ground(matrix_sample):
    dataset = MatrixDataset(matrix_sample)
    cam = dataset.reference_camera('D3')
    probes = np.array(
        [
            [5.0, -5.0, 0.0],  # plaza ground
            [15.0, -15.0, 8.0],  # the block's body, 8 m up (its ground ray lands behind it)
            [15.0, -19.0, 0.0],  # ground right behind the block: hidden
            [-8.0, -15.0, 0.0],
        ]
    )  # ground outside the area
    uv = cam.project(probes)
    assert np.all(cam.in_image(uv))
    keep = ground_pixels(cam, np.vstack([uv, [[960.0, 0.0]]]), dataset.area, 0.0, MATRIX_BLOCK)
    assert keep.tolist() == [True, False, False, False, False]  # last probe: top row of the image


def _pitched_down(cam: Camera, degrees: float) -> Camera:
    """``cam`` rotated about its own x axis so that it looks ``degrees`` further down (same centre, K, dist)."""
    R = cv2.Rodrigues(np.array([np.radians(degrees), 0.0, 0.0]))[0] @ cam.R
    return Camera(cam.K, pose_matrix(R, -R @ cam.center), cam.width, cam.height, cam.dist)


def test_block_close_above_the_camera_hides_only_what_is_behind_it(matrix_sample):
    # Regression: drone 8 of the real sample, pitched 9.6 deg further down (37 deg, as drones fly on other
    # frames of the dataset): the block's top corners, 30 m up, lie near the camera's principal plane and
    # the (real, tiny) lens distortion flings their projections to v ~ 43000 and 65000 px. The mask built
    # from projected corners then covered the whole image and no ground point was visible.
    dataset = MatrixDataset(matrix_sample)
    cam = _pitched_down(dataset.camera('D8', 0), 9.6)
    x0, y0, x1, y1, h = MATRIX_BLOCK
    top = cam.project(np.array([[x0, y0, h], [x0, y1, h]]))
    assert np.all(top[:, 1] > 20000)  # the camera of the bug report
    world = visible_ground_grid(cam, dataset.area, 0.5, MATRIX_BLOCK)
    assert len(world) > 2000
    visible = {tuple(p) for p in world}
    # Ground between the drone (x = -4.4, y = -15) and the block is visible; behind the block it is not.
    assert all((x, -15.0) in visible for x in np.arange(3.0, 12.5, 0.5))
    assert not any((x, -15.0) in visible for x in np.arange(13.0, 30.5, 0.5))
    hidden_by_block = np.array([[20.0, -15.0], [25.0, -14.0], [29.0, -16.0]])
    assert np.all(cam.in_image(cam.ground_to_img(hidden_by_block)))  # in view, so the block is why
    # The same per-ray test decides which reference pixels are ground features.
    probes = np.array(
        [
            [5.0, -15.0, 0.0],  # ground in front of the block
            [10.0, -12.0, 0.0],  # ground in front of the block
            [12.5, -15.0, 5.0],  # the block's front face
            [20.0, -15.0, 0.0],
        ]
    )  # ground behind the block
    keep = ground_pixels(cam, cam.project(probes), dataset.area, 0.0, MATRIX_BLOCK)
    assert keep.tolist() == [True, True, False, False]


def test_ground_mask_matches_line_of_sight_on_every_sample_camera(matrix_sample):
    # The mask is exactly "the segment camera -> ground point misses the block", whatever the projection.
    dataset = MatrixDataset(matrix_sample)
    for view in dataset.views:
        cam = dataset.camera(view, 0)
        all_in_view = visible_ground_grid(cam, dataset.area, 1.0)
        world = visible_ground_grid(cam, dataset.area, 1.0, MATRIX_BLOCK)
        blocked = segments_blocked(cam.center, np.c_[all_in_view, np.zeros(len(all_in_view))], MATRIX_BLOCK)
        assert {tuple(p) for p in world} == {tuple(p) for p in all_in_view[~blocked]}
        assert 0 < blocked.sum() < len(all_in_view)
