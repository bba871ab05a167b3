"""Distractors: static objects the detector must learn to IGNORE, placed at random per sequence.

Posts with coloured spheres (one at each area corner, as in the real scene, plus random ones), plain
poles, thick columns, lamp posts, bollards, bins and trees are vertical bodies (:class:`Round`: stacked
cylinders and spheres on one axis, drawn like people); benches and parked cars are boxes
(:class:`~matrix_core.sim.config.BoxConfig`, drawn, shadowed and occluding like the block). Distractors are
never annotated and write 0 into the id buffer.

Placement keeps the ground truth exact without special cases:
- near the area (between its border and the drone ring) and inside it only thin or low objects stand;
  inside ones become crowd obstacles (:func:`crowd_obstacles`), so nobody walks through them;
- tall or wide objects (trees, lamp posts, cars) stand beyond the drone ring (max-norm distance from the
  centre larger than any drone's plus the object's footprint), so they can never be between a camera and
  a person in the area (the segment from a drone to a person lies inside the drone ring's square);
- every distractor's bounding box counts in line of sight (:meth:`Distractors.round_boxes`); nothing stands on a
  checkerboard.

Convention: internal world metres, z up; colours BGR.
"""

from dataclasses import dataclass, field

import numpy as np

from matrix_core.sim.config import BoxConfig

# Saturated sphere colours (BGR) like the real corner markers: orange, blue, magenta, green, yellow, red, cyan.
SPHERE_COLORS = [
    (0, 120, 245),
    (200, 80, 20),
    (190, 40, 200),
    (40, 170, 40),
    (0, 210, 235),
    (30, 30, 210),
    (210, 200, 30),
]
POST_COLORS = [(30, 30, 90), (40, 40, 45), (90, 90, 95), (160, 160, 165), (30, 60, 40)]
CAR_COLORS = [(40, 40, 45), (200, 200, 205), (60, 40, 150), (120, 70, 30), (130, 130, 135), (30, 30, 30)]
THIN_KINDS = ('pole', 'bollard', 'post_sphere', 'bin')  # allowed inside the area
NEAR_KINDS = THIN_KINDS + ('bench', 'column')  # between the area and the drone ring
FAR_KINDS = ('tree', 'lamp', 'car', 'bench', 'pole', 'post_sphere', 'bin', 'bollard', 'column')


@dataclass
class Round:
    """A vertical body: ``cylinders`` [(radius, z0, z1, BGR)] then ``spheres`` [(z, radius, BGR)] on the
    axis at ``xy`` (2,), drawn in that order (a sphere on its post, a crown on its trunk)."""

    kind: str
    xy: np.ndarray
    cylinders: list = field(default_factory=list)
    spheres: list = field(default_factory=list)

    @property
    def radius(self) -> float:
        """Footprint radius (metres) of the widest part."""
        return max([c[0] for c in self.cylinders] + [s[1] for s in self.spheres])

    @property
    def top(self) -> float:
        return max([c[2] for c in self.cylinders] + [s[0] + s[1] for s in self.spheres])


def _round(kind: str, xy, rng: np.random.Generator, sphere_color=None) -> Round:
    """One vertical distractor of ``kind`` with random dimensions and colours."""
    post = tuple(float(v) for v in POST_COLORS[rng.integers(len(POST_COLORS))])
    if kind == 'post_sphere':  # a post ~1-1.5 m carrying a 0.4-0.6 m saturated sphere
        h, r = rng.uniform(1.0, 1.5), rng.uniform(0.2, 0.3)
        color = sphere_color or SPHERE_COLORS[rng.integers(len(SPHERE_COLORS))]
        return Round(kind, xy, [(rng.uniform(0.06, 0.12), 0.0, h, post)], [(h + r * 0.8, r, color)])
    if kind == 'pole':
        return Round(kind, xy, [(rng.uniform(0.05, 0.12), 0.0, rng.uniform(3.0, 6.0), post)])
    if kind == 'column':  # like the real dark-red cylinders near the area corners (~0.5 m x 3 m)
        return Round(kind, xy, [(rng.uniform(0.2, 0.3), 0.0, rng.uniform(2.5, 3.5), post)])
    if kind == 'lamp':
        h = rng.uniform(4.0, 6.0)
        return Round(kind, xy, [(0.08, 0.0, h, post)], [(h, rng.uniform(0.18, 0.3), (200, 235, 250))])
    if kind == 'bollard':  # people-sized width on purpose
        h, r = rng.uniform(0.8, 1.2), rng.uniform(0.12, 0.22)
        return Round(kind, xy, [(r, 0.0, h, post)], [(h, r, post)] if rng.random() < 0.5 else [])
    if kind == 'bin':
        color = tuple(float(v) for v in rng.choice([(40, 90, 40), (50, 50, 55), (30, 80, 160), (120, 120, 125)]))
        return Round(kind, xy, [(rng.uniform(0.25, 0.35), 0.0, rng.uniform(0.8, 1.1), color)])
    if kind == 'tree':
        trunk_h, crown = rng.uniform(2.0, 3.5), rng.uniform(1.2, 2.2)
        green = tuple(float(v) for v in (rng.uniform(30, 60), rng.uniform(80, 120), rng.uniform(40, 70)))
        return Round(
            kind,
            xy,
            [(rng.uniform(0.12, 0.22), 0.0, trunk_h + crown * 0.5, (40, 55, 70))],
            [(trunk_h + crown, crown, green)],
        )
    raise ValueError(f'unknown distractor kind {kind!r}')


def _box(kind: str, xy, rng: np.random.Generator) -> BoxConfig:
    """A bench (low box) or a parked car (car-sized box), along x or y at random."""
    if kind == 'bench':
        size, height = [rng.uniform(1.4, 2.0), rng.uniform(0.45, 0.6)], rng.uniform(0.45, 0.55)
        color = [float(v) for v in rng.choice([(40, 70, 110), (60, 60, 65), (30, 50, 80)])]
    else:
        size, height = [rng.uniform(3.8, 4.8), rng.uniform(1.7, 1.9)], rng.uniform(1.4, 1.6)
        color = [float(v) for v in CAR_COLORS[rng.integers(len(CAR_COLORS))]]
    if rng.random() < 0.5:
        size = size[::-1]
    return BoxConfig(
        center=[float(xy[0]), float(xy[1])], size=[float(s) for s in size], height=float(height), color=color
    )


def _footprint(item) -> tuple:
    """(x0, y0, x1, y1) ground bounds of a Round or a BoxConfig."""
    if isinstance(item, Round):
        (x, y), r = item.xy, item.radius
        return (x - r, y - r, x + r, y + r)
    return item.bounds


def _overlaps(a, b, margin: float) -> bool:
    return a[0] - margin < b[2] and b[0] - margin < a[2] and a[1] - margin < b[3] and b[1] - margin < a[3]


class Distractors:
    """The distractors of one sequence.

    Args:
        config: :class:`~matrix_core.sim.config.SceneConfig` (uses ``distractors``, area, block, pillars,
            boards, drones, building_distance).
        rng: the distractor generator (child 4 of the sequence seed); None for no distractors.

    Attributes:
        rounds: list of :class:`Round`; boxes: list of BoxConfig (benches, cars); inside: the subset of
        both standing in the walkable area (crowd obstacles).
    """

    def __init__(self, config, rng: np.random.Generator):
        self.rounds, self.boxes, self.inside, self._near_rounds = [], [], [], []
        cfg = config.distractors
        if rng is None or cfg is None or not cfg.enabled:
            return
        cx, cy = config.center
        ax0, ay0, ax1, ay1 = config.area
        self._taken = [b.bounds for b in config.obstacles] + [b.bounds for b in config.boards]
        if cfg.corner_posts:  # one post with a sphere just outside each area corner, distinct colours
            colors = rng.permutation(len(SPHERE_COLORS))
            for k, (x, y, sx, sy) in enumerate(
                [(ax0, ay0, -1, -1), (ax1, ay0, 1, -1), (ax1, ay1, 1, 1), (ax0, ay1, -1, 1)]
            ):
                for _ in range(20):  # just outside the corner, off the diagonal when a pillar stands there
                    off = rng.uniform(0.5, 2.0, 2)
                    item = _round(
                        'post_sphere',
                        np.array([x + sx * off[0], y + sy * off[1]]),
                        rng,
                        SPHERE_COLORS[colors[k % len(colors)]],
                    )
                    if self._add(item, margin=0.2):
                        break
        half_area = max(ax1 - cx, ay1 - cy)
        drones = config.drones
        ring_out = max(drones.ring_half_side, drones.reference_ring_half_side) + drones.target_xy + 0.5
        outer = config.building_distance - 1.5
        for _ in range(cfg.inside):
            self._place(rng, THIN_KINDS, cx, cy, 0.0, half_area - 1.0, inside=True)
        for _ in range(cfg.near):
            self._place(rng, NEAR_KINDS, cx, cy, half_area + 0.8, ring_out - 1.0)
        n_near = len(self.rounds)
        for _ in range(cfg.far):
            self._place(rng, FAR_KINDS, cx, cy, ring_out, outer, far=True)
        self._near_rounds = self.rounds[:n_near]

    def _add(self, item, margin: float) -> bool:
        box = _footprint(item)
        if any(_overlaps(box, t, margin) for t in self._taken):
            return False
        self._taken.append(box)
        (self.rounds if isinstance(item, Round) else self.boxes).append(item)
        return True

    def _place(self, rng, kinds, cx, cy, r_min, r_max, inside=False, far=False) -> None:
        """Try a few random spots in the square band r_min <= max(|dx|, |dy|) <= r_max (``far``: the whole
        footprint beyond r_min) for one object of a random kind; skip it when none is free."""
        kind = kinds[rng.integers(len(kinds))]
        for _ in range(20):
            dx, dy = rng.uniform(-r_max, r_max, 2)
            if max(abs(dx), abs(dy)) < r_min:
                continue
            xy = np.array([cx + dx, cy + dy])
            item = _box(kind, xy, rng) if kind in ('bench', 'car') else _round(kind, xy, rng)
            x0, y0, x1, y1 = _footprint(item)
            if far and not (x0 - cx >= r_min or cx - x1 >= r_min or y0 - cy >= r_min or cy - y1 >= r_min):
                continue  # some part within the drone ring's square: could stand between a camera and a person
            if max(abs(x0 - cx), abs(x1 - cx), abs(y0 - cy), abs(y1 - cy)) > r_max + 1.0:
                continue
            if self._add(item, margin=1.5 if inside else 0.5):
                if inside:
                    self.inside.append(item)
                return

    def round_boxes(self) -> list:
        """The vertical distractors within the drone ring as ((x0, y0, x1, y1), height) bounding boxes for
        line of sight (those beyond it can never stand between a camera and the area; the box distractors
        are scene boxes already)."""
        return [(_footprint(r), r.top) for r in self._near_rounds]

    def crowd_obstacles(self, margin: float = 0.1) -> list:
        """BoxConfig footprints of the distractors inside the area, grown by ``margin`` (crowd obstacles)."""
        out = []
        for item in self.inside:
            x0, y0, x1, y1 = _footprint(item)
            out.append(
                BoxConfig(
                    center=[(x0 + x1) / 2, (y0 + y1) / 2], size=[x1 - x0 + 2 * margin, y1 - y0 + 2 * margin], height=1.0
                )
            )
        return out


def shadow_hulls(rounds, offset) -> list:
    """Per Round: (M, 2) ground points whose convex hull is its sun shadow (footprint circle and every
    part's top circle displaced by ``offset`` (2,) metres per metre of height)."""
    ring = np.stack(
        [np.cos(np.linspace(0, 2 * np.pi, 8, endpoint=False)), np.sin(np.linspace(0, 2 * np.pi, 8, endpoint=False))],
        axis=1,
    )
    hulls = []
    for r in rounds:
        pts = [r.xy + ring * r.cylinders[0][0]] if r.cylinders else []
        pts += [r.xy + ring * rad + offset * z1 for rad, _, z1, _ in r.cylinders]
        pts += [r.xy + ring * rad + offset * z for z, rad, _ in r.spheres]
        hulls.append(np.concatenate(pts))
    return hulls
