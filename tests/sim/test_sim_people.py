"""Articulated pedestrians of the simulator: walking pose, looks, crowd gait state, and the exactness of the
ground truth (annotation box and foot point) against the drawn body (id buffer)."""

import cv2
import numpy as np
import pytest

from matrix_core.sim.appearance import person_looks
from matrix_core.sim.config import VARIANTS, CrowdConfig, load_scene_config
from matrix_core.sim.crowd import ReplayCrowd
from matrix_core.sim.ground_truth import CYLINDER_HEIGHT_M, annotation_box
from matrix_core.sim.person_model import PARTS, STRIDE, SWING_DEG, body_rings, gait_phase, max_reach, swing_amplitude
from matrix_core.sim.render import People
from matrix_core.sim.sequence import Simulation
from matrix_core.sim.visibility import line_of_sight

PX = 2.0  # rasterisation slack (LINE_8 fills and circles), pixels


@pytest.fixture(scope='module', params=[(640, 360), (1920, 1080)], ids=['640', '1920'])
def sim(request):
    cv2.setNumThreads(1)
    s = Simulation(load_scene_config('complex'), seed=11, width=request.param[0], height=request.param[1])
    s.step(1.0)
    return s


def _cylinder_box(cam, xy, radius, height):
    """(x0, y0, x1, y1) of the projected vertical cylinder (``radius``, ``height``) standing at ``xy``."""
    a = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    ring = np.c_[xy[0] + radius * np.cos(a), xy[1] + radius * np.sin(a)]
    uv = cam.project(np.concatenate([np.c_[ring, np.zeros(48)], np.c_[ring, np.full(48, height)]]))
    return uv[:, 0].min(), uv[:, 1].min(), uv[:, 0].max(), uv[:, 1].max(), uv[:48, 1]


def _random_people(rng, n, cam, walking=True):
    """``n`` people standing on random ground points seen in the central part of ``cam``'s image."""
    uv = np.c_[rng.uniform(0.15, 0.85, n) * cam.width, rng.uniform(0.35, 0.9, n) * cam.height]
    pos = cam.backproject_to_ground(uv)[:, :2]
    return People(
        np.arange(n),
        pos,
        rng.uniform(1.5, 1.95, n),
        person_looks(rng, n)[0],
        headings=rng.uniform(-np.pi, np.pi, n),
        phases=rng.uniform(0, 2 * np.pi, n),
        swings=np.full(n, np.radians(SWING_DEG)) if walking else None,
        dress=rng.random(n) < 0.3,
    )


@pytest.mark.parametrize('walking', [True, False])
def test_drawn_body_within_bounded_annotation_box_and_foot_at_bottom(sim, walking):
    """For random people and cameras, the drawn body (id buffer) of a lone person:
    - lies inside the projected cylinder of :func:`max_reach` (the documented excess over the 0.16 m x
      1.8 m MATRIX cylinder: swinging feet/hands and shoulders sideways, heads of people taller than 1.8 m);
    - has most of its pixels inside the MATRIX annotation box (grown by PX): what exceeds it is the
      swinging feet and hands, the shoulders (0.19 m + the arm, wider than 0.16 m) and heads above 1.8 m;
    - has its bottom at the foot point: no higher than it, and no lower than the farthest foot can reach
      (standing: within the foot's own size)."""
    rng = np.random.default_rng(3 if walking else 4)
    checked, inside_share = 0, []
    for k in range(len(sim.views)):
        cam = sim.camera(k)
        people = _random_people(rng, 8, cam, walking)
        vis = line_of_sight(cam, people.positions, sim.scene.occluders)
        for j in np.flatnonzero(vis):
            one = People(
                np.array([0]),
                people.positions[j : j + 1],
                people.heights[j : j + 1],
                people.colors[j : j + 1],
                headings=people.headings[j : j + 1],
                phases=people.phases[j : j + 1],
                swings=None if people.swings is None else people.swings[j : j + 1],
                dress=people.dress[j : j + 1],
            )
            _, ids = sim.renderer.render(cam, one)
            vs, us = np.nonzero(ids == 1)
            if (
                len(vs) == 0
                or us.min() == 0
                or vs.min() == 0
                or us.max() == cam.width - 1
                or vs.max() == cam.height - 1
            ):
                continue  # (partly) outside the image or hidden by the block
            xy, h = people.positions[j], people.heights[j]
            reach, top = max_reach(h)
            bx0, by0, bx1, by1, ground_v = _cylinder_box(cam, xy, reach, max(top, CYLINDER_HEIGHT_M))
            assert bx0 - PX <= us.min() and us.max() <= bx1 + PX, f'view {k} person {j}: too wide'
            assert by0 - PX <= vs.min(), f'view {k} person {j}: too tall'
            box = annotation_box(cam, xy)
            inside = (us >= box.xmin - PX) & (us <= box.xmax + PX) & (vs >= box.ymin - PX) & (vs <= box.ymax + PX)
            inside_share.append(inside.mean())
            foot_v = cam.project(np.array([[xy[0], xy[1], 0.0]]))[0, 1]
            low = ground_v.max() if walking else _cylinder_box(cam, xy, 0.12, 0.0)[4].max()
            assert foot_v - PX <= vs.max() <= low + PX, f'view {k} person {j}: bottom {vs.max()} vs {foot_v}'
            checked += 1
    assert checked >= 30
    print(f'checked {checked}, inside share median {np.median(inside_share):.3f} min {min(inside_share):.3f}')
    assert np.median(inside_share) > (0.9 if walking else 0.97)
    assert min(inside_share) > (0.7 if walking else 0.85)


def test_walking_pose_geometry():
    n = 50
    rng = np.random.default_rng(0)
    pos, h = rng.uniform(0, 10, (n, 2)), rng.uniform(1.5, 1.95, n)
    heading, phase = rng.uniform(-np.pi, np.pi, n), rng.uniform(0, 2 * np.pi, n)
    fwd = np.c_[np.cos(heading), np.sin(heading)]
    for amp in (0.0, np.radians(SWING_DEG)):
        rings, centers, normals = body_rings(pos, h, heading, phase, np.full(n, amp))
        feet = centers[:, [PARTS['leg_l'][1] - 1, PARTS['leg_r'][1] - 1], :]
        assert np.allclose(feet[..., 2], 0.0)
        assert np.allclose(feet[..., :2].mean(axis=1), pos), 'the position is the midpoint between the feet'
        spread = np.einsum('nd,nd->n', feet[:, 0, :2] - feet[:, 1, :2], fwd)
        assert np.allclose(spread, 2 * np.sin(amp * np.sin(phase)) * 0.5 * h, atol=1e-9)
        hands = centers[:, [PARTS['arm_l'][1] - 1, PARTS['arm_r'][1] - 1], :2]
        arm_spread = np.einsum('nd,nd->n', hands[:, 0] - hands[:, 1], fwd)
        assert np.all(arm_spread * spread <= 1e-12), 'arms swing opposite to the legs'
        assert np.isclose(np.linalg.norm(normals, axis=-1), 1.0).all()
        assert rings[..., 2].max() < h.max() and (rings[..., 2] >= 0).all()
    shoulders = np.ptp(rings[:, PARTS['torso'][0] + 1, :, :2] @ np.array([0.0, 1.0]), axis=1)
    assert shoulders.max() < 0.5, 'slim torso'


def test_gait_phase_and_swing():
    h = np.array([1.5, 1.75, 1.95])
    ids = np.arange(3)
    assert np.allclose(gait_phase(STRIDE * h, h, ids) - gait_phase(np.zeros(3), h, ids), 2 * np.pi)
    assert not np.allclose(np.diff(gait_phase(np.zeros(3), h, ids)), 0.0), 'people are out of step'
    amp = swing_amplitude(np.array([0.0, 0.3, 1.2, 2.0]))
    assert amp[0] == 0.0 and 0 < amp[1] < amp[2] and np.isclose(amp[3], np.radians(SWING_DEG))


def test_crowd_exposes_walking_state(sim):
    crowd = sim.crowd
    before_pos, before_walked = crowd.positions.copy(), crowd.walked.copy()
    crowd.step(0.1)
    step = crowd.positions - before_pos
    dist = np.linalg.norm(step, axis=1)
    assert np.allclose(crowd.walked - before_walked, dist)
    assert np.allclose(crowd.speeds, dist / 0.1)
    moving = dist > 0.01
    assert moving.sum() > len(dist) // 2
    assert np.allclose(crowd.headings[moving], np.arctan2(step[moving, 1], step[moving, 0]))


class _Replay:
    root = 'fake'
    trajectory_frames = (0, 1, 2)

    def pedestrian_positions(self, frame):
        return {3: (1.0 + frame, 2.0, 0.0), 7: (5.0, 5.0 - 0.5 * frame, 0.0)}


def test_replay_crowd_derives_heading_from_positions():
    crowd = ReplayCrowd(_Replay(), np.random.default_rng(0))
    assert (1.5 <= crowd.heights).all() and (crowd.heights <= 1.95).all()
    crowd.step(0.5)
    assert np.allclose(crowd.headings, [0.0, -np.pi / 2])
    assert np.allclose(crowd.walked, [1.0, 0.5]) and np.allclose(crowd.speeds, [2.0, 1.0])


def test_looks_are_seeded_dark_and_varied():
    a, da = person_looks(np.random.default_rng(1), 400)
    b, db = person_looks(np.random.default_rng(1), 400)
    assert (a == b).all() and (da == db).all()
    assert a.shape == (400, 4, 3) and a.dtype == np.uint8
    trousers = a[~da, 1].astype(float).mean(axis=1)
    assert np.median(trousers) < 80, 'suits are mostly dark'
    assert 0.1 < da.mean() < 0.3 and (a[:, 0].astype(float).mean(axis=1) > 130).mean() > 0.05
    assert len({tuple(c) for c in a[:, 2] // 16}) > 4, 'several skin tones'
    assert not person_looks(np.random.default_rng(1), 50, dress_fraction=0.0)[1].any()


def test_lit_side_is_brighter():
    """One standing person in the middle of the simple square, seen from the drone nearest the sun's side
    and from the one opposite: the body (without the head) is brighter seen from the lit side."""
    s = Simulation(load_scene_config('simple'), seed=0, width=640, height=360)
    centre = np.array(s.config.center)
    sun = s.renderer.light.direction
    light_xy = sun[:2] / np.linalg.norm(sun[:2])
    cams = [s.camera(k) for k in range(len(s.views))]
    side = [float((c.center[:2] - centre) @ light_xy) / np.linalg.norm(c.center[:2] - centre) for c in cams]
    colors = np.array([[[120, 120, 120], [120, 120, 120], [120, 120, 120], [120, 120, 120]]], np.uint8)
    means = []
    for k in (int(np.argmax(side)), int(np.argmin(side))):
        people = People(np.array([0]), centre[None], np.array([1.75]), colors, headings=np.array([0.3]))
        img, ids = s.renderer.render(cams[k], people)
        vs, us = np.nonzero(ids == 1)
        body = vs > vs.min() + 0.15 * np.ptp(vs)
        means.append(img[vs[body], us[body]].astype(float).mean())
    assert means[0] > means[1] + 15, means


def test_simulation_people_are_deterministic():
    renders = []
    for _ in range(2):
        s = Simulation(load_scene_config('complex'), seed=2, width=320, height=180)
        s.step(1.0)
        renders.append(s.render_view(3)[1:3])
        people = s.people()
        assert people.dress is not None and people.swings.max() > 0
    assert (renders[0][0] == renders[1][0]).all() and (renders[0][1] == renders[1][1]).all()


def test_walking_pose_can_be_switched_off():
    cfg = load_scene_config('simple')
    cfg.crowd.walking_pose = False
    s = Simulation(cfg, seed=0, width=320, height=180)
    s.step(1.0)
    assert s.people().swings is None and s.crowd.speeds.max() > 0.5


@pytest.mark.parametrize('variant', VARIANTS)
def test_heights_default_and_variants(variant):
    assert CrowdConfig().height_range == [1.5, 1.95]
    assert load_scene_config(variant).crowd.height_range == [1.5, 1.95]
