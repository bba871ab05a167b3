"""Distractors, ground materials and facade styles: seeded, switchable, and the ground truth stays exact
(distractors are never annotated, never hide an annotated person unnoticed, never stand on a board or in
a walker's way)."""

import dataclasses

import cv2
import numpy as np
import pytest

from matrix_core.sim.config import VARIANTS, DistractorConfig, load_scene_config
from matrix_core.sim.distractors import Round
from matrix_core.sim.ground_truth import annotation_box
from matrix_core.sim.render import People
from matrix_core.sim.sequence import Simulation


def _plain(cfg):
    return dataclasses.replace(cfg, distractors=DistractorConfig(enabled=False))


def _footprint(item):
    if isinstance(item, Round):
        (x, y), r = item.xy, item.radius
        return (x - r, y - r, x + r, y + r)
    return item.bounds


@pytest.fixture(scope='module')
def sim():
    cv2.setNumThreads(1)
    s = Simulation(load_scene_config('complex'), seed=21, width=640, height=360)
    s.step(1.0)
    return s


def test_shipped_variants_have_distractors_on():
    for variant in VARIANTS:
        cfg = load_scene_config(variant)
        assert cfg.distractors.enabled
        scene = Simulation(cfg, seed=1, width=320, height=180).scene
        assert len(scene.rounds) >= 10 and scene.facade_style in ('dusk', 'day')


def test_same_seed_same_scene_other_seed_differs():
    cfg = load_scene_config('complex')
    a, b, c = (Simulation(cfg, seed=s, width=320, height=180) for s in (4, 4, 5))
    assert [tuple(r.xy) for r in a.scene.rounds] == [tuple(r.xy) for r in b.scene.rounds]
    assert [tuple(r.xy) for r in a.scene.rounds] != [tuple(r.xy) for r in c.scene.rounds]
    img_a, img_b = a.render_view(0)[1], b.render_view(0)[1]
    assert np.array_equal(img_a, img_b)
    # the drones, crowd start and looks do not depend on the randomisation (separate child streams)
    p = Simulation(_plain(cfg), seed=4, width=320, height=180)
    assert np.allclose(p.camera(0).center, a.camera(0).center)


def test_disabled_gives_the_plain_scene():
    cfg = _plain(load_scene_config('complex'))
    p = Simulation(cfg, seed=4, width=320, height=180)
    assert p.scene.rounds == [] and p.scene.distractors.boxes == [] and p.scene.facade_style is None
    assert len(p.scene.boxes) == len(cfg.obstacles) and p.scene.crowd_config() is cfg


def test_corner_posts_and_placement(sim):
    cfg = sim.config
    ax0, ay0, ax1, ay1 = cfg.area
    posts = [r for r in sim.scene.rounds if r.kind == 'post_sphere' and r.spheres]
    for x, y in ((ax0, ay0), (ax1, ay0), (ax1, ay1), (ax0, ay1)):
        assert min(np.linalg.norm(r.xy - [x, y]) for r in posts) < 2.0
    d = cfg.drones
    ring = max(d.ring_half_side, d.reference_ring_half_side) + d.target_xy
    cx, cy = cfg.center
    taken = [b.bounds for b in cfg.boards] + [b.bounds for b in cfg.obstacles]
    for item in sim.scene.rounds + sim.scene.distractors.boxes:
        x0, y0, x1, y1 = _footprint(item)
        for t in taken:  # nothing on a checkerboard or in the block
            assert x1 <= t[0] or t[2] <= x0 or y1 <= t[1] or t[3] <= y0
        # anything taller or wider than a thin object stays outside the drone ring's square
        big = isinstance(item, Round) and item.kind in ('tree', 'lamp') or getattr(item, 'height', 0) > 1.0
        if big:
            assert x0 - cx >= ring or cx - x1 >= ring or y0 - cy >= ring or cy - y1 >= ring
    assert len(sim.scene.distractors.inside) >= 1


def test_people_never_walk_through_inside_distractors():
    s = Simulation(load_scene_config('complex'), seed=3, width=320, height=180)
    boxes = [_footprint(item) for item in s.scene.distractors.inside]
    assert boxes
    for _ in range(20):
        s.step(0.5)
        for x0, y0, x1, y1 in boxes:
            dx = np.maximum(np.maximum(x0 - s.crowd.positions[:, 0], s.crowd.positions[:, 0] - x1), 0.0)
            dy = np.maximum(np.maximum(y0 - s.crowd.positions[:, 1], s.crowd.positions[:, 1] - y1), 0.0)
            assert np.hypot(dx, dy).min() >= s.config.crowd.leg_radius


def test_distractors_are_never_annotated(sim):
    """Distractor pixels are 0 in the id buffer: the empty scene has none, and every annotation comes from
    a person."""
    for k in range(len(sim.views)):
        img, ids = sim.renderer.render(sim.camera(k), None)
        assert not ids.any()
    plain = Simulation(_plain(sim.config), seed=21, width=640, height=360)
    assert not np.array_equal(
        plain.renderer.render(plain.camera(0), None)[0], sim.renderer.render(sim.camera(0), None)[0]
    )


def test_annotated_people_are_seen_and_boxes_hold_their_foot_point(sim):
    """Each person the line of sight calls visible shows pixels when rendered alone with every distractor
    (so no distractor hides it unnoticed), and its annotation box ends on its foot point."""
    p = sim.people()
    checked = 0
    for k in range(0, len(sim.views), 2):
        cam, _, _, visible = sim.render_view(k)
        for n in np.flatnonzero(visible):
            alone = People(
                p.ids[n : n + 1],
                p.positions[n : n + 1],
                p.heights[n : n + 1],
                p.colors[n : n + 1],
                p.leg_radius,
                p.body_radius,
            )
            _, ids = sim.renderer.render(cam, alone)
            assert (ids == p.ids[n] + 1).sum() > 0, f'view {k}: person {p.ids[n]} hidden by a distractor'
            box = annotation_box(cam, p.positions[n])
            foot = cam.project(np.array([[*p.positions[n], 0.0]]))[0]
            assert box.xmin <= foot[0] <= box.xmax and abs(box.ymax - foot[1]) < 1e-6
            checked += 1
    assert checked > 50


def test_ground_and_facade_styles_vary_per_seed():
    cfg = load_scene_config('complex')
    styles = {Simulation(cfg, seed=s, width=160, height=90).scene.facade_style for s in range(8)}
    assert styles == {'dusk', 'day'}
    a, b = (Simulation(cfg, seed=s, width=320, height=180).scene.ground_levels[0][0] for s in (1, 2))
    assert a.shape == b.shape and not np.array_equal(a, b)


def test_marker_hidden_by_a_distractor_is_not_listed():
    """A column standing between a camera and a board corner hides the corner in the image and drops it
    from the listed plane points."""
    from matrix_core.sim.ground_truth import visible_markers
    from matrix_core.sim.visibility import rays_blocked

    s = Simulation(load_scene_config('complex'), seed=2, width=640, height=360)
    cam = s.camera(0)
    ids, uv = visible_markers(cam, s.scene.marker_ids, s.scene.marker_xyz, s.scene.occluders, rays_blocked)
    target = s.scene.marker_xyz[list(s.scene.marker_ids).index(ids[len(ids) // 2])]
    toward = cam.center[:2] - target[:2]
    xy = target[:2] + toward / np.linalg.norm(toward) * 1.5
    column = Round('column', xy, [(0.3, 0.0, 4.0, (200.0, 30.0, 30.0))])
    s.scene.rounds.append(column)
    s.scene.distractors._near_rounds.append(column)
    ids2, _ = visible_markers(cam, s.scene.marker_ids, s.scene.marker_xyz, s.scene.occluders, rays_blocked)
    hidden = set(ids) - set(ids2)
    assert ids[len(ids) // 2] in hidden and set(ids2) <= set(ids)
    img, _ = s.renderer.render(cam, None)
    u, v = np.round(uv[len(ids) // 2]).astype(int)
    b, r = int(img[v, u, 0]), int(img[v, u, 2])
    assert b > 60 and b - r > 40, (b, r)  # the column's blue (under this sequence's light), not the board
