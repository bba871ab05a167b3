"""Procedural textures: the top-down ground image (cement or cobblestone, markings) and building facades.

Textures are functions of WORLD coordinates sampled at ``m_per_px``, so a lower-resolution render samples
the same pattern more coarsely (the seed fixes the pattern, the resolution only its sampling).

Convention (ground texture): texture pixel (col, row) has its CENTRE at world
``x = x_min + col * m_per_px``, ``y = y_max - row * m_per_px`` (north up), see :func:`tex_H_ground`.
"""

from dataclasses import dataclass

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
    big = cv2.resize(
        lattice,
        (int(round(n_c * cell_m / m_per_px)), int(round(n_r * cell_m / m_per_px))),
        interpolation=cv2.INTER_CUBIC,
    )
    return big[:rows, :cols]


def _world_axes(extent, shape, m_per_px):
    x_min, _, _, y_max = extent
    rows, cols = shape
    return (x_min + np.arange(cols, dtype=np.float32) * m_per_px, y_max - np.arange(rows, dtype=np.float32) * m_per_px)


def _bond_shade(extent, shape, m_per_px, rng, w, h, joint, spread, joint_shade, running=True) -> np.ndarray:
    """(rows, cols) float32 shade offsets of a stone/tile bond: ``w`` x ``h`` metre units (rows shifted by
    half a unit when ``running``), each offset by +- ``spread``, joints of ``joint`` metres at
    ``joint_shade``."""
    xs, ys = _world_axes(extent, shape, m_per_px)
    row_idx = np.floor(ys / h).astype(np.int64)
    x_shift = (row_idx % 2) * (w / 2) if running else np.zeros_like(row_idx)
    u = xs[None, :] + x_shift[:, None].astype(np.float32)
    col_idx = np.floor(u / w).astype(np.int64)
    table = rng.uniform(-spread, spread, 4096).astype(np.float32)
    shade = table[((col_idx * 73856093) ^ (row_idx[:, None] * 19349663)) & 4095]
    fu = u - col_idx * w
    fv = (ys - row_idx * h)[:, None]
    in_joint = (np.minimum(fu, w - fu) < joint / 2) | (np.minimum(fv, h - fv) < joint / 2)
    shade[in_joint] = joint_shade
    return shade


def _cobblestone_shade(extent, shape, m_per_px, rng) -> np.ndarray:
    """(rows, cols) float32 shade offsets: running-bond stones of 0.22 x 0.14 m with dark joints."""
    return _bond_shade(extent, shape, m_per_px, rng, 0.22, 0.14, 0.025, 28.0, -55.0)


@dataclass
class GroundStyle:
    """Random per-sequence ground look (see :func:`ground_style`): materials and colours (BGR) of the
    walkable area and of its surround, dirt patches, extra painted lines."""

    inside: str  # cement | tiles | cobblestone | asphalt
    inside_color: tuple
    tile_m: float
    surround: str  # pavers | asphalt | cobblestone
    surround_color: tuple
    dirt: float  # strength of dark dirt patches (shade units)
    dirt_tint: tuple  # BGR multiplier of dirt (brownish)
    road_lines: int  # painted lines across the surround


def ground_style(rng: np.random.Generator, config) -> GroundStyle:
    """Draw a :class:`GroundStyle`: mostly light concrete inside like the real square, sometimes tiles,
    cobblestone or asphalt; a darker paving, asphalt or cobblestone surround."""
    inside = str(rng.choice(['cement', 'tiles', 'cobblestone', 'asphalt', config.floor], p=[0.3, 0.3, 0.1, 0.1, 0.2]))
    base = np.asarray(config.floor_color, dtype=float)
    if inside == 'asphalt':
        base = np.full(3, rng.uniform(70, 105))
    elif inside in ('cement', 'tiles'):
        base = np.full(3, rng.uniform(150, 200)) + rng.uniform(-6, 6, 3)
    surround = str(rng.choice(['pavers', 'asphalt', 'cobblestone']))
    s_tone = rng.uniform(60, 100) if surround == 'asphalt' else rng.uniform(95, 145)
    s_base = np.full(3, s_tone) + rng.uniform(-8, 8, 3)
    return GroundStyle(
        inside,
        tuple(base),
        float(rng.uniform(0.4, 1.0)),
        surround,
        tuple(s_base),
        float(rng.uniform(8.0, 30.0)),
        tuple(rng.uniform([0.88, 0.94, 0.98], [0.96, 0.99, 1.02])),
        int(rng.integers(0, 4)),
    )


def _material_shade(material, extent, shape, m_per_px, rng, tile_m) -> np.ndarray:
    if material == 'cobblestone':
        return _cobblestone_shade(extent, shape, m_per_px, rng)
    if material == 'tiles':
        return _bond_shade(extent, shape, m_per_px, rng, tile_m, tile_m, 0.012, 12.0, -22.0, running=False)
    if material == 'pavers':
        return _bond_shade(extent, shape, m_per_px, rng, 0.4, 0.2, 0.015, 14.0, -30.0)
    if material == 'asphalt':  # fine aggregate grain
        return 9.0 * value_noise(shape, m_per_px, 0.03, rng)
    return np.zeros(shape, dtype=np.float32)


def _line_mask(extent, shape, m_per_px, positions, width_m, axis: int) -> np.ndarray:
    """(rows, cols) bool: lines of ``width_m`` at the given x (axis 0) or y (axis 1) positions."""
    xs, ys = _world_axes(extent, shape, m_per_px)
    coord = xs if axis == 0 else ys
    hit = np.zeros(coord.shape, dtype=bool)
    for p in positions:
        hit |= np.abs(coord - p) < max(width_m / 2, m_per_px / 2)
    return np.broadcast_to(hit[None, :] if axis == 0 else hit[:, None], shape)


def ground_texture(config, extent, m_per_px: float, rng: np.random.Generator, style: GroundStyle = None) -> np.ndarray:
    """Top-down (rows, cols, 3) BGR uint8 image of the whole ground within ``extent`` (no checkerboards:
    those are drawn as exact polygons by the renderer).

    Without ``style``: the walkable area gets ``config.floor`` in ``config.floor_color``, outside it a darker
    surround of 2 m tiles. With a :class:`GroundStyle`: its materials, colours, dirt and painted lines.
    """
    if style is not None:
        return _styled_ground(config, extent, m_per_px, rng, style)
    shape, xs, ys, inside, shade = _ground_base(config, extent, m_per_px, rng)
    if config.floor == 'cobblestone':
        shade += np.where(inside, _cobblestone_shade(extent, shape, m_per_px, rng), 0.0)
    # Stains: dark blotches give the registration stage distinctive, non-repeating features.
    stains = value_noise(shape, m_per_px, 1.5, rng)
    shade -= 22.0 * np.clip(stains - 0.55, 0.0, None) / 0.45
    floor = np.asarray(config.floor_color, dtype=np.float32)
    surround = np.array([128, 132, 135], dtype=np.float32)
    img = np.where(inside[..., None], floor, surround) + shade[..., None]

    if config.markings:
        _paint_markings(img, config, extent, m_per_px, xs, ys, inside)
    # Tiles of the surround: a 2 m grid of thin joints.
    sx = _line_mask(extent, shape, m_per_px, np.arange(np.floor(extent[0]), extent[2], 2.0), 0.04, 0)
    sy = _line_mask(extent, shape, m_per_px, np.arange(np.floor(extent[1]), extent[3], 2.0), 0.04, 1)
    img[(sx | sy) & ~inside] *= 0.75
    return np.clip(img, 0, 255).astype(np.uint8)


def _ground_base(config, extent, m_per_px, rng) -> tuple:
    """What every ground texture starts from: (shape, xs (cols,), ys (rows,) texel-centre world coordinates,
    inside (rows, cols) bool area mask, shade (rows, cols) float multi-scale grain; the registration matches
    the grain's features)."""
    shape = texture_shape(extent, m_per_px)
    xs, ys = _world_axes(extent, shape, m_per_px)
    ax0, ay0, ax1, ay1 = config.area
    inside = ((xs[None, :] >= ax0) & (xs[None, :] <= ax1)) & ((ys[:, None] >= ay0) & (ys[:, None] <= ay1))
    shade = (
        9.0 * value_noise(shape, m_per_px, 5.0, rng)
        + 7.0 * value_noise(shape, m_per_px, 0.7, rng)
        + 4.0 * value_noise(shape, m_per_px, 0.12, rng)
        + 5.0 * value_noise(shape, m_per_px, 0.01, rng)
    )
    return shape, xs, ys, inside, shade


def _paint_markings(img, config, extent, m_per_px, xs, ys, inside) -> None:
    """Paint the area's joint lines (a 4 x 4 grid, darker) and its dark outline into ``img`` (rows, cols, 3)
    float, in place; ``xs``/``ys`` are the texel centres' world coordinates, ``inside`` the area mask."""
    shape = img.shape[:2]
    ax0, ay0, ax1, ay1 = config.area
    cx, cy = config.center
    half_w = (ax1 - ax0) / 2
    joints = [cx + d for d in np.arange(-half_w, half_w + 1e-6, (ax1 - ax0) / 4)]
    joints_y = [cy + d for d in np.arange(-half_w, half_w + 1e-6, (ay1 - ay0) / 4)]
    lines = _line_mask(extent, shape, m_per_px, joints, 0.08, 0) | _line_mask(
        extent, shape, m_per_px, joints_y, 0.08, 1
    )
    img[lines & inside] *= 0.62
    outline = _line_mask(extent, shape, m_per_px, [ax0, ax1], 0.3, 0) | _line_mask(
        extent, shape, m_per_px, [ay0, ay1], 0.3, 1
    )
    box = (
        (xs[None, :] >= ax0 - 0.2)
        & (xs[None, :] <= ax1 + 0.2)
        & (ys[:, None] >= ay0 - 0.2)
        & (ys[:, None] <= ay1 + 0.2)
    )
    img[outline & box] = (55, 55, 58)


def _styled_ground(config, extent, m_per_px, rng, style: GroundStyle) -> np.ndarray:
    shape, xs, ys, inside, shade = _ground_base(config, extent, m_per_px, rng)
    ax0, ay0, ax1, ay1 = config.area
    shade += np.where(
        inside,
        _material_shade(style.inside, extent, shape, m_per_px, rng, style.tile_m),
        _material_shade(style.surround, extent, shape, m_per_px, rng, style.tile_m),
    )
    stains = value_noise(shape, m_per_px, 1.5, rng)
    shade -= 22.0 * np.clip(stains - 0.55, 0.0, None) / 0.45
    dirt = np.clip(value_noise(shape, m_per_px, 4.0, rng) - 0.5, 0.0, None) / 0.5  # large dirty patches
    img = (
        np.where(
            inside[..., None], np.asarray(style.inside_color, np.float32), np.asarray(style.surround_color, np.float32)
        )
        + shade[..., None]
    )
    img -= (style.dirt * dirt)[..., None]
    img *= 1.0 + (np.asarray(style.dirt_tint, np.float32) - 1.0) * np.minimum(dirt * 2.0, 1.0)[..., None]
    if config.markings:
        _paint_markings(img, config, extent, m_per_px, xs, ys, inside)
    for _ in range(style.road_lines):  # painted lines in the surround (white or yellow, dashed or not)
        axis = int(rng.integers(2))
        lo, hi = (extent[0], ax0) if rng.random() < 0.5 else (ax1, extent[2])
        if axis == 1:
            lo, hi = (extent[1], ay0) if rng.random() < 0.5 else (ay1, extent[3])
        pos = rng.uniform(lo + 1.0, hi - 1.0) if hi - lo > 2.0 else (lo + hi) / 2
        mask = _line_mask(extent, shape, m_per_px, [pos], rng.uniform(0.1, 0.2), axis) & ~inside
        if rng.random() < 0.5:
            along = ys[:, None] if axis == 0 else xs[None, :]
            mask = mask & (np.mod(along, 3.0) < 1.5)
        img[mask] = (215, 215, 215) if rng.random() < 0.6 else (60, 190, 220)
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


def facade_texture(rng: np.random.Generator, width_m: float, height_m: float, px_per_m: float = 8.0) -> np.ndarray:
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
    img[int((height_m - 3.5) * px_per_m) :] *= 0.7
    return np.clip(img, 0, 255).astype(np.uint8)


def facade_style(rng: np.random.Generator) -> str:
    """Per-sequence backdrop: 'dusk' (dark facades, bright warm lit windows, as in the real frames) or
    'day' (lighter facades, dark glass)."""
    return 'dusk' if rng.random() < 0.6 else 'day'


def styled_facade_texture(
    rng: np.random.Generator, width_m: float, height_m: float, style: str, px_per_m: float = 8.0
) -> np.ndarray:
    """(rows, cols, 3) BGR facade of a ``style`` (see :func:`facade_style`) with random storey height,
    window size and spacing, and often a street-level shop front (glass band under a coloured sign).
    Row 0 is the TOP of the facade."""
    cols, rows = max(8, int(width_m * px_per_m)), max(8, int(height_m * px_per_m))
    dusk = style == 'dusk'
    tone = rng.uniform(25, 60) if dusk else rng.uniform(90, 185)
    base = tone * rng.uniform([0.85, 0.9, 0.95], [1.0, 1.05, 1.25])
    img = np.empty((rows, cols, 3), dtype=np.float32)
    img[:] = base
    img += (5.0 if dusk else 10.0) * value_noise((rows, cols), 1.0 / px_per_m, 1.0, rng)[..., None]
    floor_h, win_w, win_h = rng.uniform(2.8, 3.6), rng.uniform(0.8, 1.8), rng.uniform(1.2, 2.0)
    spacing = max(win_w + 0.4, rng.uniform(2.0, 3.8))
    lit_p = rng.uniform(0.25, 0.7)
    shop = rng.random() < 0.6
    first = 4.2 if shop else floor_h
    z = first + 0.8
    while z + win_h < height_m - 0.5:  # window rows, from the bottom up
        r0, r1 = int((height_m - z - win_h) * px_per_m), int((height_m - z) * px_per_m)
        for k in range(int(width_m // spacing)):
            x0 = (k + 0.5) * spacing - win_w / 2
            c0, c1 = int(x0 * px_per_m), int((x0 + win_w) * px_per_m)
            if dusk:
                lit = rng.random() < lit_p
                color = rng.uniform([110, 190, 235], [170, 230, 255]) if lit else rng.uniform(10, 30, 3)
            else:
                color = rng.uniform([60, 55, 45], [120, 110, 100])
            cv2.rectangle(img, (c0, r0), (c1, r1), tuple(float(v) for v in color), -1)
        z += floor_h
    if shop:  # glass shop fronts, a sign band above
        top = int((height_m - 3.0) * px_per_m)
        glass = rng.uniform([120, 190, 230], [180, 235, 255]) if dusk else rng.uniform([50, 50, 45], [90, 85, 80])
        img[top:] = glass
        for c in range(0, cols, max(2, int(rng.uniform(2.0, 4.0) * px_per_m))):  # mullions
            img[top:, c : c + 2] = base * 0.6
        sign = np.array(rng.uniform(20, 230, 3), dtype=np.float32)
        img[int((height_m - 3.8) * px_per_m) : top] = sign
    else:
        img[int((height_m - 3.5) * px_per_m) :] *= 0.7
    return np.clip(img, 0, 255).astype(np.uint8)
