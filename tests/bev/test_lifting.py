"""Homography lifting on the real sample's calibrations: a ground point lands in its own BEV cell."""

import numpy as np
import pytest
import torch

import torch.nn.functional as F

from matrix_core.bev.lifting import feat_H_grid, lifting_taps, orient_ground_homography, sampling_grid, warp_to_grid
from matrix_core.bev.settings import BevSettings
from matrix_core.datasets import open_dataset

torch.set_num_threads(1)


@pytest.fixture(scope='module')
def sample(matrix_sample):
    ds = open_dataset(matrix_sample)
    return ds, BevSettings().grid(ds.area)


@pytest.mark.parametrize('view', ['D1', 'D4', 'D7'])
def test_known_ground_point_lands_in_its_cell(sample, view):
    """Features that hold their own feature-pixel coordinates (exact under bilinear sampling), warped to
    the grid, must give at each person's cell the feature pixel where OpenCV projects that cell's centre."""
    ds, grid = sample
    cam = ds.camera(view, 2)
    input_size, stride = (480, 272), 4
    fh, fw = input_size[1] // stride, input_size[0] // stride
    H = feat_H_grid(cam.img_H_ground(), grid.ground_H_grid, (cam.width, cam.height), input_size, stride)
    v, u = torch.meshgrid(torch.arange(fh, dtype=torch.float64), torch.arange(fw, dtype=torch.float64), indexing='ij')
    bev, seen = warp_to_grid(torch.stack([u, v])[None], torch.from_numpy(H)[None], grid.shape)
    checked = 0
    for person in ds.annotations(2):
        if view not in person.boxes:
            continue
        col, row = np.floor(grid.world_to_cell(person.world_xy)[0] + 0.5).astype(int)
        centre = grid.cell_to_world(np.array([[col, row]], float))[0]
        assert np.abs(centre - person.world_xy).max() <= grid.cell / 2 + 1e-9
        uv = cam.project(np.r_[centre, 0.0][None])[0]  # full-resolution pixel, via cv2.projectPoints
        fu = (uv[0] + 0.5) * input_size[0] / cam.width / stride - 0.5
        fv = (uv[1] + 0.5) * input_size[1] / cam.height / stride - 0.5
        if not (0 <= fu <= fw - 1 and 0 <= fv <= fh - 1):
            continue  # near the border the ramp is clamped
        assert seen[0, 0, row, col] == 1
        np.testing.assert_allclose(bev[0, :, row, col].numpy(), [fu, fv], atol=1e-4)
        checked += 1
    assert checked >= 15


def test_cells_behind_the_camera_are_not_seen(sample):
    ds, grid = sample
    cam = ds.camera('D1', 0)  # D1 at about (-4.7, -4.7) internal (-4.7, 4.7): sees +x, -y
    H = feat_H_grid(cam.img_H_ground(), grid.ground_H_grid, (cam.width, cam.height), (480, 272), 4)
    feats = torch.ones(1, 1, 68, 120, dtype=torch.float64)
    _, seen = warp_to_grid(feats, torch.from_numpy(H)[None], grid.shape)
    centre = cam.center[:2]
    cells = grid.cell_to_world(
        np.stack(np.meshgrid(np.arange(grid.nx), np.arange(grid.ny)), -1).reshape(-1, 2).astype(float)
    )
    depth = cam.depth(np.c_[cells, np.zeros(len(cells))]).reshape(grid.shape)
    s = seen[0, 0].numpy()
    assert s[depth <= 0].sum() == 0  # nothing behind the camera
    assert 0.2 < s.mean() < 0.95  # a real part of the grid, not all of it
    # a registration homography may come with the opposite sign: lifting must not care
    H2 = feat_H_grid(-cam.img_H_ground(), grid.ground_H_grid, (cam.width, cam.height), (480, 272), 4)
    np.testing.assert_allclose(H2, H)
    assert np.allclose(orient_ground_homography(-cam.img_H_ground(), (1920, 1080)), cam.img_H_ground())
    assert np.linalg.norm(cells[np.argmax(s.reshape(-1))] - centre) > 1.0


def test_lifting_taps_sample_as_grid_sample(sample):
    """FrameNetwork's lifting (the taps gathered by F.embedding_bag from channels-last maps) against grid_sample on
    sampling_grid's points: every real view of two frames, and a view turned away from the ground (nothing seen)."""
    ds, grid = sample
    input_size, stride = (320, 176), 4
    h, w = input_size[1] // stride, input_size[0] // stride
    fhs = [
        feat_H_grid(ds.camera(v, f).img_H_ground(), grid.ground_H_grid, (1920, 1080), input_size, stride)
        for f in (0, 4)
        for v in ds.views
    ]
    away = fhs[0].copy()
    away[2] *= -1.0  # every cell behind the camera
    fhs = torch.tensor(np.stack(fhs + [away]), dtype=torch.float32)
    maps = torch.rand(len(fhs), 16, h, w, generator=torch.Generator().manual_seed(0))
    index, weight, seen = lifting_taps(fhs, (h, w), grid.shape)
    offsets = (torch.arange(len(fhs)) * h * w)[:, None, None]
    lifted = F.embedding_bag(
        (index + offsets).reshape(-1, 4),
        maps.permute(0, 2, 3, 1).reshape(-1, 16),
        per_sample_weights=weight.reshape(-1, 4),
        mode='sum',
    )
    lifted = lifted.reshape(len(fhs), *grid.shape, 16).permute(0, 3, 1, 2)
    points, seen_grid = sampling_grid(fhs, (h, w), grid.shape)
    expected = F.grid_sample(maps, points, mode='bilinear', padding_mode='zeros', align_corners=False)
    torch.testing.assert_close(lifted, expected, atol=1e-4, rtol=0)
    assert torch.equal(seen, seen_grid.reshape(len(fhs), -1))
    assert seen[:-1].sum(dim=1).min() > 0.2 * seen.shape[1] and seen[-1].sum() == 0
    assert weight[-1].abs().max() == 0 and index.min() >= 0 and index.max() < h * w
    # cells whose point lies in the outer half pixel: the taps outside the map weigh nothing, as grid_sample's
    border = seen.bool()[:-1] & (weight[:-1] > 0).sum(dim=-1).lt(4) & weight[:-1].sum(dim=-1).lt(0.999)
    assert border.sum() > 0
