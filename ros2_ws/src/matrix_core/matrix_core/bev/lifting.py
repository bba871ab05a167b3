"""Lifting image features onto the BEV grid with each frame's own image-to-ground homography.

Convention:
    - ``img``: full-resolution image pixels (pixel centres, see ``geometry/camera.py``);
    - ``feat``: pixels of a feature map that covers the image with ``stride`` input pixels per feature
      pixel after the image was resized to the network input size (pixel centres as well);
    - ``grid``: BEV cell indices (col, row), see :class:`~matrix_core.geometry.grid.BevGrid`.
    ``feat_H_grid`` maps grid cells to feature pixels; it is what :func:`warp_to_grid` samples with.
"""

import numpy as np
import torch
import torch.nn.functional as F

from matrix_core.geometry.homography import pixel_scale_homography


def orient_ground_homography(img_H_ground: np.ndarray, image_size: tuple) -> np.ndarray:
    """Fix the overall sign of a ground homography so that its third output is the (positive) depth of
    points in front of the camera, as ``Camera.img_H_ground`` gives it.

    A homography estimated up to scale (e.g. by registration) may come with either sign; the image
    centre of a camera looking down sees the ground in front of it, so its ground point must have a
    positive homogeneous coordinate.
    """
    w, h = image_size
    g = np.linalg.solve(img_H_ground, np.array([(w - 1) / 2.0, (h - 1) / 2.0, 1.0]))
    return img_H_ground if g[2] > 0 else -img_H_ground


def feat_H_grid(
    img_H_ground: np.ndarray, ground_H_grid: np.ndarray, image_size: tuple, input_size: tuple, stride: int
) -> np.ndarray:
    """(3, 3) homography from BEV cells to feature-map pixels.

    Args:
        img_H_ground: (3, 3) ground metres -> full-resolution image pixels (this frame's calibration).
        ground_H_grid: (3, 3) grid cells -> ground metres (``BevGrid.ground_H_grid``).
        image_size: (width, height) of the full-resolution image.
        input_size: (width, height) the image is resized to before the encoder.
        stride: input pixels per feature pixel.
    """
    img_H_ground = orient_ground_homography(np.asarray(img_H_ground, dtype=np.float64), image_size)
    img_H_input = pixel_scale_homography(image_size[0] / input_size[0], image_size[1] / input_size[1])
    input_H_feat = pixel_scale_homography(stride, stride)
    feat_H_img = np.linalg.inv(img_H_input @ input_H_feat)
    return feat_H_img @ img_H_ground @ ground_H_grid


def _feature_points(feat_H_grid: torch.Tensor, feat_size: tuple, grid_shape: tuple) -> tuple:
    """(u, v, seen), each (N, rows * cols): the feature pixel every cell projects to, and whether it lies in front
    of the camera and inside the (h, w) = ``feat_size`` map. The one projection :func:`sampling_grid` and
    :func:`lifting_taps` share."""
    h, w = feat_size
    rows, cols = grid_shape
    dt = feat_H_grid.dtype if feat_H_grid.is_floating_point() else torch.float32
    at = {'dtype': dt, 'device': feat_H_grid.device}
    r, c = torch.meshgrid(torch.arange(rows, **at), torch.arange(cols, **at), indexing='ij')
    cells = torch.stack([c, r, torch.ones_like(c)], dim=-1).reshape(1, -1, 3)  # (1, R*C, 3)
    uvw = cells @ feat_H_grid.to(dt).transpose(1, 2)  # (N, R*C, 3)
    depth = uvw[..., 2]
    in_front = depth > 1e-9
    uv = uvw[..., :2] / torch.where(in_front, depth, torch.ones_like(depth)).unsqueeze(-1)
    u, v = uv[..., 0], uv[..., 1]
    return u, v, in_front & (u >= -0.5) & (u <= w - 0.5) & (v >= -0.5) & (v <= h - 0.5)


def sampling_grid(feat_H_grid: torch.Tensor, feat_size: tuple, grid_shape: tuple) -> tuple:
    """Where :func:`warp_to_grid` samples: (grid (N, rows, cols, 2) for ``F.grid_sample`` (align_corners=False),
    seen (N, 1, rows, cols) float). ``feat_H_grid`` (N, 3, 3) as in :func:`warp_to_grid`, ``feat_size`` (h, w)
    of the feature maps. A cell not seen gets a grid point far outside the map (sampled as 0)."""
    h, w = feat_size
    rows, cols = grid_shape
    u, v, inside = _feature_points(feat_H_grid, feat_size, grid_shape)
    # grid_sample with align_corners=False: -1 and +1 are the outer edges of the border pixels.
    norm = torch.stack([(u + 0.5) / w * 2 - 1, (v + 0.5) / h * 2 - 1], dim=-1)
    norm = torch.where(inside.unsqueeze(-1), norm, torch.full_like(norm, -2.0))
    n = feat_H_grid.shape[0]
    return norm.reshape(n, rows, cols, 2), inside.reshape(n, 1, rows, cols).to(u.dtype)


def lifting_taps(feat_H_grid: torch.Tensor, feat_size: tuple, grid_shape: tuple) -> tuple:
    """Where :func:`warp_to_grid` reads, as pixel indices and weights: for each cell of each view the four
    neighbouring feature pixels that ``F.grid_sample`` (bilinear, zeros padding, align_corners=False) interpolates
    at the point :func:`sampling_grid` gives it.

    Args:
        feat_H_grid: (N, 3, 3) float32 grid cells -> feature pixels, depth-positive (see :func:`feat_H_grid`).
        feat_size: (h, w) of the feature maps.
        grid_shape: (rows, cols) of the BEV grid.

    Returns:
        index (N, rows * cols, 4) long, ``y * w + x`` of each neighbour; weight (N, rows * cols, 4) float, its
        bilinear weight, 0 for a neighbour outside the map and for every neighbour of a cell not seen (index
        then within the map, any); seen (N, rows * cols) float, as :func:`sampling_grid`'s.

    ``F.embedding_bag(index + k * h * w, maps.permute(0, 2, 3, 1).reshape(-1, C), per_sample_weights=weight,
    mode='sum')`` then samples map ``k`` of (N, C, h, w) ``maps`` as grid_sample does, to float rounding (~1e-5
    here), each tap's C channels one contiguous row of channels-last maps.
    """
    h, w = feat_size
    u, v, seen = _feature_points(feat_H_grid, feat_size, grid_shape)
    u, v = torch.where(seen, u, -1.0), torch.where(seen, v, -1.0)  # far points: no overflow below
    x0, y0 = u.floor(), v.floor()
    fx, fy = u - x0, v - y0
    seen = seen.to(feat_H_grid.dtype)
    wx0, wx1 = (1 - fx) * (x0 >= 0), fx * (x0 <= w - 2)
    wy0, wy1 = (1 - fy) * (y0 >= 0) * seen, fy * (y0 <= h - 2) * seen
    weight = torch.stack([wx0 * wy0, wx1 * wy0, wx0 * wy1, wx1 * wy1], dim=-1)
    corners = torch.tensor([0, 1, w, w + 1], device=u.device)
    index = ((y0 * w + x0).long().unsqueeze(-1) + corners).clamp_(0, h * w - 1)
    return index, weight, seen


def warp_to_grid(features: torch.Tensor, feat_H_grid: torch.Tensor, grid_shape: tuple) -> tuple:
    """Sample feature maps at every BEV cell.

    Args:
        features: (N, C, h, w) feature maps (N = batch x views).
        feat_H_grid: (N, 3, 3) grid cells -> feature pixels, depth-positive (see :func:`feat_H_grid`).
        grid_shape: (rows, cols) of the BEV grid.

    Returns:
        (bev (N, C, rows, cols), seen (N, 1, rows, cols) float): ``seen`` is 1 where the cell lies in front
        of the camera and inside the feature map; ``bev`` is 0 elsewhere (sampled far outside the map).
    """
    grid, seen = sampling_grid(feat_H_grid.to(features.dtype), features.shape[-2:], grid_shape)
    bev = F.grid_sample(features, grid, mode='bilinear', padding_mode='zeros', align_corners=False)
    return bev, seen
