"""A site file as a simulator scene: its area, boards and obstacles in a :class:`SceneConfig`, and its drones as
a :class:`~matrix_core.sim.drones.DroneRig` (where each flies, its own camera, its reference pose).

Where a drone flies (its home, the point its random targets are drawn around, and its reference pose):

1. the site gives its reference (``references.source: files``): home and reference pose are the reference
   calibration's camera (read from the site's files);
2. else the drone's ``home`` and ``altitude_m``, where the site gives them; the reference pose hovers at home,
   aimed at the area centre;
3. else a ring around the area centre: drones without a home are spread evenly on a circle of
   ``ring_radius`` (0: the area's half diagonal, as MATRIX's ring is its square's) at ``altitude`` (0: the
   scene config's ``drones.altitude``).

Cameras: each drone's ``camera`` of the site, scaled by ``image_scale`` (image size rounded, K scaled about
the pixel-centre origin). Convention: internal world metres, pixel-centre pixels.
"""

import dataclasses
from dataclasses import dataclass

import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.sim.config import BoxConfig
from matrix_core.sim.drones import DroneRig
from matrix_core.site.schema import ReferenceSource, Site


@dataclass
class SiteBoardConfig:
    """A site's board as the simulator draws it: ``squares`` x ``squares_y`` squares of ``square_m`` from the
    (x_min, y_min) corner ``origin`` on the plane z = ``z``; square (i, j) counted from ``origin`` is black
    when ``i + j + parity`` is even (the site's light/dark layout, whichever way its axes run)."""

    name: str
    origin: list
    squares: int
    squares_y: int
    square_m: float
    z: float
    parity: int

    @property
    def squares_xy(self) -> tuple:
        return (self.squares, self.squares_y)

    @property
    def dark_parity(self) -> int:
        return self.parity

    @property
    def bounds(self) -> tuple:
        x0, y0 = self.origin
        return (x0, y0, x0 + self.squares * self.square_m, y0 + self.squares_y * self.square_m)


def _axis(v) -> int:
    """0 for +-x, 1 for +-y, ValueError otherwise (the renderer draws boards aligned with the ground axes)."""
    v = np.asarray(v, float)
    for k in (0, 1):
        if abs(abs(v[k]) - 1.0) < 1e-9 and abs(v[1 - k]) < 1e-9 and abs(v[2]) < 1e-9:
            return k
    raise ValueError(f'axis {list(v)} is not +-x or +-y')


def board_config(board) -> SiteBoardConfig:
    """The :class:`SiteBoardConfig` of a site's :class:`~matrix_core.calib.board.Checkerboard` (same squares,
    same colours); ValueError naming the board when its axes are not the ground's x and y."""
    try:
        ki, kj = _axis(board.axis_i), _axis(board.axis_j)
    except ValueError as exc:
        raise ValueError(f'board {board.name}: the simulator draws boards along the ground axes: {exc}') from None
    # outer edge: one square beyond the outermost inner corners
    edge = board.points([-1, board.nx, -1, board.nx], [-1, -1, board.ny, board.ny])
    lo = edge[:, :2].min(axis=0)
    n = {ki: board.nx + 1, kj: board.ny + 1}
    # the colour of the site's cell (0, 0) fixes the parity: its centre is at corner coordinates (-0.5, -0.5)
    centre = board.points([-0.5], [-0.5])[0, :2]
    p, q = np.floor((centre - lo) / board.square + 1e-9).astype(int)
    black = not board.first_cell_light
    parity = int((p + q) % 2 if black else (p + q + 1) % 2)
    return SiteBoardConfig(
        board.name, [float(lo[0]), float(lo[1])], n[0], n[1], float(board.square), float(board.origin[2]), parity
    )


def scene_for_site(site: Site, base, drone_homes: np.ndarray):
    """``base`` (a :class:`SceneConfig`: crowd, light, camera effects, distractors) with the site's area, boards
    and obstacles, and the drone ring and buildings set around ``drone_homes`` (N, 3)."""
    cx, cy = (site.area[0] + site.area[2]) / 2, (site.area[1] + site.area[3]) / 2
    ring = float(np.max(np.abs(np.asarray(drone_homes)[:, :2] - [cx, cy]))) if len(drone_homes) else 1.0
    pillars = [
        BoxConfig(
            center=[(o.footprint[0] + o.footprint[2]) / 2, (o.footprint[1] + o.footprint[3]) / 2],
            size=[o.footprint[2] - o.footprint[0], o.footprint[3] - o.footprint[1]],
            height=o.height,
        )
        for o in site.obstacles
    ]
    # the base's spacing between its drone ring and its facades, kept around the site's drones
    spacing = max(base.building_distance - base.drones.ring_half_side, 6.0)
    drones = dataclasses.replace(
        base.drones,
        count=len(site.drones),
        ring_half_side=ring,
        reference_ring_half_side=ring,
        altitude=float(np.mean(np.asarray(drone_homes)[:, 2])),
        hfov_deg=float(np.mean([d.camera.hfov_deg for d in site.drones])),
    )
    return dataclasses.replace(
        base,
        name=site.name,
        area=list(site.area),
        block=None,
        pillars=pillars,
        boards=[board_config(b) for b in site.boards],
        drones=drones,
        building_distance=ring + drones.target_xy + spacing,
    )


def scaled_camera(K: np.ndarray, size: tuple, scale: float) -> tuple:
    """(K (3, 3), (w, h)) of a camera rendered at ``scale`` of its size: pixel-centre coordinates scale about
    the centre of pixel (0, 0)'s corner, u' = (u + 0.5) s - 0.5."""
    if scale == 1.0:
        return np.asarray(K, float).copy(), tuple(size)
    w, h = max(1, round(size[0] * scale)), max(1, round(size[1] * scale))
    sx, sy = w / size[0], h / size[1]
    S = np.array([[sx, 0.0, 0.5 * sx - 0.5], [0.0, sy, 0.5 * sy - 0.5], [0.0, 0.0, 1.0]])
    return S @ np.asarray(K, float), (w, h)


def site_rig(site: Site, image_scale: float, ring_radius: float, altitude: float) -> DroneRig:
    """The site's drones (module docstring for where each flies); ``altitude`` must be > 0 when a drone needs
    the ring. Reading a reference calibration raises the site's SiteError."""
    from matrix_core.site.references import reference_camera

    x0, y0, x1, y1 = site.area
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    radius = ring_radius or float(np.hypot(x1 - x0, y1 - y0) / 2)
    on_ring = [d.name for d in site.drones if d.home_xy is None and site.references is not ReferenceSource.FILES]
    homes, Ks, sizes, refs = [], [], [], []
    for d in site.drones:
        K, size = scaled_camera(d.camera.K, d.camera.image_size, image_scale)
        ref = None
        if site.references is ReferenceSource.FILES:
            cam = reference_camera(site, d)
            RK, _ = scaled_camera(cam.K, d.camera.image_size, image_scale)
            ref = Camera(RK, cam.cam_T_world, size[0], size[1])
            home = cam.center
        elif d.home_xy is not None:
            home = np.array([*d.home_xy, d.altitude_m or altitude])
        else:
            a = 2 * np.pi * on_ring.index(d.name) / len(on_ring) - np.pi / 2  # the first one south of the centre
            home = np.array([*(centre + radius * np.array([np.cos(a), np.sin(a)])), d.altitude_m or altitude])
        if not home[2] > 0:
            raise ValueError(f'drone {d.name}: no altitude (the site gives no altitude_m; pass --altitude)')
        homes.append(np.asarray(home, float))
        Ks.append(K)
        sizes.append(size)
        refs.append(ref)
    return DroneRig(site.drone_names, np.array(homes).reshape(-1, 3), tuple(Ks), tuple(sizes), tuple(refs))
