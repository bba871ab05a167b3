"""Crowd motion: a small social-force model, or a replay of recorded trajectories.

Each pedestrian walks at its preferred speed (about 1.2 m/s) toward a random goal in the area, detouring
around the obstacles (via the nearest corner of the inflated box when the straight path is blocked),
repelled by the others, the obstacles and the area border, and never entering an obstacle or leaving the
area (hard constraints applied after each integration step). A new goal is drawn when one is reached.

Convention: internal world metres; positions are (N, 2) ground points (x, y), person ids 0..N-1.
"""

import numpy as np

SUBSTEP_S = 0.1
RELAX_S = 0.5  # time to reach the preferred velocity
# Repulsion strength (m/s^2), range (m) and contact distance (m). The contact distance matches the real MATRIX
# crowd (the sample's 500 frames of trajectories, scripts/crowd_stats.py): nearest neighbour 1st / 5th percentile
# 1.00 / 1.09 m there, 0.98 / 1.10 m here; with 0.6 m (before) people came within 0.53 / 0.70 m, walked into each
# other and bounced back, which the real crowd never does and which merged two people into one detection.
PERSON_A, PERSON_B, PERSON_R = 3.0, 0.25, 1.1
WALL_A, WALL_B = 4.0, 0.25


def advance_gait(crowd, old_positions, duration: float) -> None:
    """Update ``crowd.headings`` (N,) radians, ``crowd.walked`` (N,) metres and ``crowd.speeds`` (N,) m/s
    from the move ``old_positions`` -> ``crowd.positions`` over ``duration`` seconds (what the walking pose
    needs); the heading is kept while a person barely moves."""
    step = crowd.positions - old_positions
    dist = np.linalg.norm(step, axis=1)
    moving = dist > 0.02 * duration
    crowd.headings = np.where(moving, np.arctan2(step[:, 1], step[:, 0]), crowd.headings)
    crowd.walked = crowd.walked + dist
    crowd.speeds = dist / max(duration, 1e-9)


def _inflated(bounds, margin):
    x0, y0, x1, y1 = bounds
    return (x0 - margin, y0 - margin, x1 + margin, y1 + margin)


def _inside(points, bounds) -> np.ndarray:
    x0, y0, x1, y1 = bounds
    return (points[..., 0] > x0) & (points[..., 0] < x1) & (points[..., 1] > y0) & (points[..., 1] < y1)


def segment_hits_box(a, b, bounds) -> bool:
    """Whether the segment a -> b ((2,) points) passes through the open box (x0, y0, x1, y1) (slab test)."""
    d = np.asarray(b, float) - np.asarray(a, float)
    t0, t1 = 0.0, 1.0
    for k, (lo, hi) in enumerate(((bounds[0], bounds[2]), (bounds[1], bounds[3]))):
        if abs(d[k]) < 1e-12:
            if not lo < a[k] < hi:
                return False
            continue
        ta, tb = (lo - a[k]) / d[k], (hi - a[k]) / d[k]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
        if t0 >= t1:
            return False
    return True


class Crowd:
    """Social-force crowd in ``config.area`` avoiding ``obstacles`` (list of box bounds).

    Args:
        config: :class:`~matrix_core.sim.config.SceneConfig` (uses ``area`` and ``crowd``).
        rng: random generator (start positions, goals, speeds): deterministic per seed.
    """

    def __init__(self, config, rng: np.random.Generator):
        self.rng = rng
        self.cfg = config.crowd
        m = self.cfg.keep_out_margin
        self.walk_area = _inflated(config.area, -m)
        self.obstacles = [_inflated(b.bounds, m) for b in config.obstacles]
        n = self.cfg.count
        self.speed = np.clip(rng.normal(self.cfg.speed, self.cfg.speed_std, n), 0.6, 1.8)
        self.heights = rng.uniform(*self.cfg.height_range, n)
        self.detour = rng.uniform(0.4, 2.0, n)  # how wide each person rounds an obstacle corner (no queues)
        self.positions = self._spawn(n)
        self.velocity = np.zeros((n, 2))
        self.via = [None] * n  # current detour corner per person
        self.goals = np.array([self._random_goal(p) for p in self.positions]).reshape(n, 2)
        to_goal = self.goals - self.positions
        self.headings = np.arctan2(to_goal[:, 1], to_goal[:, 0])  # walking pose (see advance_gait)
        self.walked = np.zeros(n)
        self.speeds = np.zeros(n)

    @property
    def ids(self) -> np.ndarray:
        return np.arange(len(self.positions))

    def _free(self, p) -> bool:
        return _inside(np.asarray(p), self.walk_area) and not any(
            _inside(np.asarray(p), _inflated(o, 0.2)) for o in self.obstacles
        )

    def _random_point(self) -> np.ndarray:
        x0, y0, x1, y1 = self.walk_area
        for _ in range(10000):
            p = np.array([self.rng.uniform(x0, x1), self.rng.uniform(y0, y1)])
            if self._free(p):
                return p
        raise ValueError('no free space for pedestrians: the obstacles cover the area')

    def _spawn(self, n) -> np.ndarray:
        pts = []
        for _ in range(n):
            for _ in range(1000):
                p = self._random_point()
                if all(np.linalg.norm(p - q) > PERSON_R for q in pts):
                    break
            else:
                raise ValueError(f'cannot place {n} pedestrians {PERSON_R} m apart in the area')
            pts.append(p)
        return np.array(pts).reshape(n, 2)

    def _random_goal(self, p) -> np.ndarray:
        for _ in range(100):
            g = self._random_point()
            if np.linalg.norm(g - p) > 5.0:
                return g
        return g

    def _waypoint(self, i: int) -> np.ndarray:
        """Where person ``i`` heads now: its goal, or a corner of an obstacle that blocks the straight path.

        The chosen corner is kept until reached (within 0.7 m), then the next one is chosen, so nobody
        dithers between two corners.
        """
        p, goal = self.positions[i], self.goals[i]
        blocking = [o for o in self.obstacles if segment_hits_box(p, goal, o)]
        if not blocking:
            self.via[i] = None
            return goal
        if self.via[i] is not None and np.linalg.norm(self.via[i] - p) > 0.7:
            return self.via[i]
        x0, y0, x1, y1 = _inflated(blocking[0], self.detour[i])
        corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
        reachable = [c for c in corners if not segment_hits_box(p, c, blocking[0]) and np.linalg.norm(c - p) > 0.7]
        if not reachable:
            return goal
        costs = [np.linalg.norm(c - p) + np.linalg.norm(goal - c) for c in reachable]
        self.via[i] = reachable[int(np.argmin(costs))]
        return self.via[i]

    def step(self, duration: float) -> None:
        """Advance by ``duration`` seconds in substeps of :data:`SUBSTEP_S`."""
        for _ in range(int(round(duration / SUBSTEP_S))):
            self._substep(SUBSTEP_S)

    def _substep(self, dt: float) -> None:
        pos, vel = self.positions, self.velocity
        n = len(pos)
        for i in range(n):
            if np.linalg.norm(self.goals[i] - pos[i]) < 1.0:
                self.goals[i] = self._random_goal(pos[i])
        heading = np.array([self._waypoint(i) for i in range(n)]).reshape(n, 2) - pos
        heading /= np.maximum(np.linalg.norm(heading, axis=1, keepdims=True), 1e-9)
        force = (self.speed[:, None] * heading - vel) / RELAX_S
        if n > 1:
            diff = pos[:, None, :] - pos[None, :, :]
            dist = np.linalg.norm(diff, axis=2) + np.eye(n) * 1e6
            mag = PERSON_A * np.exp((PERSON_R - dist) / PERSON_B)
            force += np.sum(mag[..., None] * diff / dist[..., None], axis=1)
        for o in self.obstacles + [None]:
            force += self._wall_force(pos, o)
        vel = vel + force * dt
        v_norm = np.linalg.norm(vel, axis=1, keepdims=True)
        vel *= np.minimum(1.0, 1.3 * self.speed[:, None] / np.maximum(v_norm, 1e-9))
        self.positions = self._constrain(pos + vel * dt)
        self.velocity = (self.positions - pos) / dt
        advance_gait(self, pos, dt)

    def _wall_force(self, pos, box) -> np.ndarray:
        """Repulsion from the outside of an obstacle box, or (box None) from the inside of the area border."""
        if box is None:
            x0, y0, x1, y1 = self.walk_area
            f = np.zeros_like(pos)
            f[:, 0] = WALL_A * (np.exp(-(pos[:, 0] - x0) / WALL_B) - np.exp(-(x1 - pos[:, 0]) / WALL_B))
            f[:, 1] = WALL_A * (np.exp(-(pos[:, 1] - y0) / WALL_B) - np.exp(-(y1 - pos[:, 1]) / WALL_B))
            return f
        x0, y0, x1, y1 = box
        closest = np.stack([np.clip(pos[:, 0], x0, x1), np.clip(pos[:, 1], y0, y1)], axis=1)
        diff = pos - closest
        dist = np.maximum(np.linalg.norm(diff, axis=1, keepdims=True), 1e-6)
        return WALL_A * np.exp(-dist / WALL_B) * diff / dist

    def _constrain(self, pos) -> np.ndarray:
        """Hard constraints: inside the walk area, outside every obstacle (pushed to the nearest face)."""
        x0, y0, x1, y1 = self.walk_area
        pos = np.stack([np.clip(pos[:, 0], x0, x1), np.clip(pos[:, 1], y0, y1)], axis=1)
        for bx0, by0, bx1, by1 in self.obstacles:
            inside = _inside(pos, (bx0, by0, bx1, by1))
            for i in np.flatnonzero(inside):
                x, y = pos[i]
                exits = [(x - bx0, (bx0, y)), (bx1 - x, (bx1, y)), (y - by0, (x, by0)), (by1 - y, (x, by1))]
                pos[i] = min(exits)[1]
        return pos


class ReplayCrowd:
    """Replays recorded positions (e.g. the real MATRIX ``matchings/Pedestrians``) frame by frame.

    Args:
        dataset: a dataset with ``pedestrian_positions(frame)`` and ``trajectory_frames``.
        height_range: body heights are drawn uniformly in it (metres).

    Heading, distance walked and speed (for the walking pose) come from successive positions.
    """

    def __init__(self, dataset, rng: np.random.Generator, height_range=(1.5, 1.95)):
        self.dataset = dataset
        self.frames = list(dataset.trajectory_frames)
        if not self.frames:
            raise ValueError(f'{dataset.root} has no matchings/Pedestrians/3d_TTTT.txt to replay')
        self.index = 0
        first = dataset.pedestrian_positions(self.frames[0])
        self._ids = np.array(sorted(first))
        self.heights = rng.uniform(*height_range, len(self._ids))
        self._load()
        n = len(self._ids)
        self.headings, self.walked, self.speeds = np.zeros(n), np.zeros(n), np.zeros(n)

    def _load(self):
        pos = self.dataset.pedestrian_positions(self.frames[self.index])
        missing = [i for i in self._ids if i not in pos]
        if missing:
            raise ValueError(f'replayed frame {self.frames[self.index]} lacks persons {missing}')
        self.positions = np.array([pos[i][:2] for i in self._ids]).reshape(-1, 2)

    @property
    def ids(self) -> np.ndarray:
        return self._ids

    def step(self, duration: float) -> None:
        if self.index + 1 >= len(self.frames):
            raise ValueError(f'the replayed trajectories end after {len(self.frames)} frames')
        self.index += 1
        old = self.positions
        self._load()
        advance_gait(self, old, duration)
