"""Procedural textures: the top-down ground image (cement or cobblestone, markings) and building facades.

Textures are functions of WORLD coordinates sampled at ``m_per_px``, so a lower-resolution render samples
the same pattern more coarsely (the seed fixes the pattern, the resolution only its sampling).

Convention (ground texture): texture pixel (col, row) has its CENTRE at world
``x = x_min + col * m_per_px``, ``y = y_max - row * m_per_px`` (north up), see :func:`tex_H_ground`.
"""

import cv2
import numpy as np


def tex_H_ground(extent, m_per_px: float) -> np.ndarray:
    """(3, 3) homography: world (x, y) metres on the ground -> texture pixels, for ``extent`` =
    (x_min, y_min, x_max, y_max)."""
    x_min, _, _, y_max = extent
    s = 1.0 / m_per_px
    return np.array([[s, 0.0, -x_min * s], [0.0, -s, y_max * s], [0.0, 0.0, 1.0]])


def texture_shape(extent, m_per_px: float) -> tuple:
    """(rows, cols) of a ground texture covering ``extent``."""
    x_min, y_min, x_max, y_max = extent
    return int(np.ceil((y_max - y_min) / m_per_px)) + 1, int(np.ceil((x_max - x_min) / m_per_px)) + 1


def value_noise(shape, m_per_px: float, cell_m: float, rng: np.random.Generator) -> np.ndarray:
    """(rows, cols) float32 smooth noise in about [-1, 1] with features of ``cell_m`` metres.

    A random lattice with ``cell_m`` spacing is upsampled bicubically; the lattice size depends only on the
    world extent, so the pattern is (nearly) the same at every ``m_per_px``.
    """
    rows, cols = shape
    n_r = int(np.ceil(rows * m_per_px / cell_m)) + 2
    n_c = int(np.ceil(cols * m_per_px / cell_m)) + 2
    lattice = rng.uniform(-1.0, 1.0, (n_r, n_c)).astype(np.float32)
    if cell_m <= 2 * m_per_px:  # finer than the sampling: plain per-pixel grain
        return rng.uniform(-1.0, 1.0, (rows, cols)).astype(np.float32)
    big = cv2.resize(lattice, (int(round(n_c * cell_m / m_per_px)), int(round(n_r * cell_m / m_per_px))),
                     interpolation=cv2.INTER_CUBIC)
    return big[:rows, :cols]


def _world_axes(extent, shape, m_per_px):
    x_min, _, _, y_max = extent
    rows, cols = shape
    return (x_min + np.arange(cols, dtype=np.float32) * m_per_px,
            y_max - np.arange(rows, dtype=np.float32) * m_per_px)


def _cobblestone_shade(extent, shape, m_per_px, rng) -> np.ndarray:
    """(rows, cols) float32 shade offsets: running-bond stones of 0.22 x 0.14 m with dark joints."""
    xs, ys = _world_axes(extent, shape, m_per_px)
    w, h, joint = 0.22, 0.14, 0.025
    row_idx = np.floor(ys / h).astype(np.int64)
    x_shift = (row_idx % 2) * (w / 2)
    u = xs[None, :] + x_shift[:, None].astype(np.float32)
    col_idx = np.floor(u / w).astype(np.int64)
    table = rng.uniform(-28.0, 28.0, 4096).astype(np.float32)
    shade = table[((col_idx * 73856093) ^ (row_idx[:, None] * 19349663)) & 4095]
    fu = u - col_idx * w
    fv = (ys - row_idx * h)[:, None]
    in_joint = (np.minimum(fu, w - fu) < joint / 2) | (np.minimum(fv, h - fv) < joint / 2)
    shade[in_joint] = -55.0
    return shade


def _line_mask(extent, shape, m_per_px, positions, width_m, axis: int) -> np.ndarray:
    """(rows, cols) bool: lines of ``width_m`` at the given x (axis 0) or y (axis 1) positions."""
    xs, ys = _world_axes(extent, shape, m_per_px)
    coord = xs if axis == 0 else ys
    hit = np.zeros(coord.shape, dtype=bool)
    for p in positions:
        hit |= np.abs(coord - p) < max(width_m / 2, m_per_px / 2)
    return np.broadcast_to(hit[None, :] if axis == 0 else hit[:, None], shape)


def ground_texture(config, extent, m_per_px: float, rng: np.random.Generator) -> np.ndarray:
    """Top-down (rows, cols, 3) BGR uint8 image of the whole ground within ``extent`` (no checkerboards:
    those are drawn as exact polygons by the renderer).

    The walkable area gets ``config.floor`` in ``config.floor_color``; outside it a darker paved surround.
    """
    shape = texture_shape(extent, m_per_px)
    xs, ys = _world_axes(extent, shape, m_per_px)
    ax0, ay0, ax1, ay1 = config.area
    inside = ((xs[None, :] >= ax0) & (xs[None, :] <= ax1)) & ((ys[:, None] >= ay0) & (ys[:, None] <= ay1))

    shade = (9.0 * value_noise(shape, m_per_px, 5.0, rng) + 7.0 * value_noise(shape, m_per_px, 0.7, rng)
             + 4.0 * value_noise(shape, m_per_px, 0.12, rng) + 5.0 * value_noise(shape, m_per_px, 0.01, rng))
    if config.floor == 'cobblestone':
        shade += np.where(inside, _cobblestone_shade(extent, shape, m_per_px, rng), 0.0)
    # Stains: dark blotches give the registration stage distinctive, non-repeating features.
    stains = value_noise(shape, m_per_px, 1.5, rng)
    shade -= 22.0 * np.clip(stains - 0.55, 0.0, None) / 0.45
    floor = np.asarray(config.floor_color, dtype=np.float32)
    surround = np.array([128, 132, 135], dtype=np.float32)
    img = np.where(inside[..., None], floor, surround) + shade[..., None]

    if config.markings:
        cx, cy = config.center
        half_w = (ax1 - ax0) / 2
        joints = [cx + d for d in np.arange(-half_w, half_w + 1e-6, (ax1 - ax0) / 4)]
        joints_y = [cy + d for d in np.arange(-half_w, half_w + 1e-6, (ay1 - ay0) / 4)]
        lines = (_line_mask(extent, shape, m_per_px, joints, 0.08, 0)
                 | _line_mask(extent, shape, m_per_px, joints_y, 0.08, 1))
        img[lines & inside] *= 0.62
        outline = (_line_mask(extent, shape, m_per_px, [ax0, ax1], 0.3, 0)
                   | _line_mask(extent, shape, m_per_px, [ay0, ay1], 0.3, 1))
        box = ((xs[None, :] >= ax0 - 0.2) & (xs[None, :] <= ax1 + 0.2)
               & (ys[:, None] >= ay0 - 0.2) & (ys[:, None] <= ay1 + 0.2))
        img[outline & box] = (55, 55, 58)
    # Tiles of the surround: a 2 m grid of thin joints.
    sx = _line_mask(extent, shape, m_per_px, np.arange(np.floor(extent[0]), extent[2], 2.0), 0.04, 0)
    sy = _line_mask(extent, shape, m_per_px, np.arange(np.floor(extent[1]), extent[3], 2.0), 0.04, 1)
    img[(sx | sy) & ~inside] *= 0.75
    return np.clip(img, 0, 255).astype(np.uint8)


def texture_pyramid(texture: np.ndarray, levels: int) -> list:
    """[texture, pyrDown(texture), ...]: level k pixel i is centred on base pixel 2^k * i (OpenCV's pyrDown
    kernel is centred on even input pixels), so level k has ``m_per_px * 2**k`` with the same origin."""
    out = [texture]
    for _ in range(levels - 1):
        if min(out[-1].shape[:2]) < 64:
            break
        out.append(cv2.pyrDown(out[-1]))
    return out


def facade_texture(rng: np.random.Generator, width_m: float, height_m: float,
                   px_per_m: float = 8.0) -> np.ndarray:
    """(rows, cols, 3) BGR facade: stone/brick colour, window grid with some lit windows, a darker ground
    floor. Row 0 is the TOP of the facade."""
    cols, rows = max(8, int(width_m * px_per_m)), max(8, int(height_m * px_per_m))
    base = np.array(rng.choice([[60, 75, 95], [95, 100, 105], [70, 85, 110], [50, 55, 60]]), dtype=np.float32)
    img = np.empty((rows, cols, 3), dtype=np.float32)
    img[:] = base
    img += 10.0 * value_noise((rows, cols), 1.0 / px_per_m, 1.0, rng)[..., None]
    floor_h, win_w = 3.2, 1.3
    spacing = rng.uniform(2.6, 3.6)
    n_floors = int(height_m // floor_h)
    for f in range(1, n_floors):
        top = height_m - f * floor_h
        for k in range(int(width_m // spacing)):
            x0 = (k + 0.5) * spacing - win_w / 2
            lit = rng.random() < 0.4
            color = (130, 200, 245) if lit else (45, 40, 38)
            r0, r1 = int((height_m - top - 0.6) * px_per_m), int((height_m - top + 1.2) * px_per_m)
            c0, c1 = int(x0 * px_per_m), int((x0 + win_w) * px_per_m)
            cv2.rectangle(img, (c0, max(r0, 0)), (c1, r1), color, -1)
    img[int((height_m - 3.5) * px_per_m):] *= 0.7
    return np.clip(img, 0, 255).astype(np.uint8)
