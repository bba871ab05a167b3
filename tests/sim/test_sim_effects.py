"""Lighting and camera effects of the simulator: seeded, switchable, pixels only (ground truth unchanged),
exact camera under supersampling, JPEG artefacts applied."""

import cv2
import numpy as np
import pytest

from matrix_core.sim import camera_effects
from matrix_core.sim.camera_effects import downsample, effective_jpeg_quality, jpeg_round_trip, supersampled_camera
from matrix_core.sim.config import LightingConfig, load_scene_config, scene_config_from_dict
from matrix_core.sim.lighting import DAY, UP, sample_lighting
from matrix_core.sim.scene import board_corners
from matrix_core.sim.sequence import Simulation


def _sim(seed=4, lighting=True, effects=True, width=640, height=360, **effects_overrides):
    cfg = load_scene_config('complex')
    cfg.lighting.enabled, cfg.camera_effects.enabled = lighting, effects
    for key, value in effects_overrides.items():
        setattr(cfg.camera_effects, key, value)
    sim = Simulation(cfg, seed=seed, width=width, height=height)
    sim.step(1.0)
    return sim


@pytest.fixture(autouse=True)
def _one_thread():
    cv2.setNumThreads(1)


def test_shipped_variants_enable_lighting_and_effects():
    for variant in ('simple', 'complex', 'modified'):
        cfg = load_scene_config(variant)
        assert cfg.lighting.enabled and cfg.camera_effects.enabled


def test_config_sections_reject_unknown_keys_and_bad_ranges():
    with pytest.raises(ValueError, match='sun_power'):
        scene_config_from_dict({'lighting': {'sun_power': 1.0}})
    with pytest.raises(ValueError, match='shadow_factor'):
        LightingConfig(shadow_factor=[0.8, 0.3])
    with pytest.raises(ValueError):
        scene_config_from_dict({'camera_effects': {'jpeg_quality': [60, 120]}})


def test_same_seed_same_images_other_seed_other_light():
    a, b, c = _sim(seed=4), _sim(seed=4), _sim(seed=5)
    for k in (0, 5):
        assert np.array_equal(a.render_view(k)[1], b.render_view(k)[1])
    assert np.array_equal(a.render_reference(2)[1], b.render_reference(2)[1])
    assert not np.allclose(a.renderer.light.direction, c.renderer.light.direction)


def test_effects_off_is_the_plain_render():
    sim = _sim(lighting=False, effects=False)
    assert sim.renderer.light is DAY
    for k in (0, 3):
        cam, img, ids, _ = sim.render_view(k)
        plain, plain_ids = sim.renderer.render(cam, sim.people())
        assert np.array_equal(img, plain) and np.array_equal(ids, plain_ids)
    # lighting on, camera effects off: still exactly the renderer's image
    lit = _sim(lighting=True, effects=False)
    cam, img, _, _ = lit.render_view(1)
    assert np.array_equal(img, lit.renderer.render(cam, lit.people())[0])


def test_effects_change_pixels_only():
    """Same seed with and without lighting/effects: same cameras, same people, same visibility and an id
    buffer that agrees almost everywhere (supersampling samples it at the output pixel centres)."""
    on, off = _sim(seed=6), _sim(seed=6, lighting=False, effects=False)
    assert np.array_equal(on.crowd.positions, off.crowd.positions)
    for k in range(len(on.views)):
        cam_on, img_on, ids_on, vis_on = on.render_view(k)
        cam_off, img_off, ids_off, vis_off = off.render_view(k)
        assert np.array_equal(cam_on.K, cam_off.K) and np.array_equal(cam_on.cam_T_world, cam_off.cam_T_world)
        assert np.array_equal(vis_on, vis_off)
        assert img_on.shape == img_off.shape and ids_on.shape == ids_off.shape
        assert (ids_on == ids_off).mean() > 0.995
        assert not np.array_equal(img_on, img_off)


def test_supersampled_camera_maps_pixel_centres():
    cam = _sim(lighting=False, effects=False).camera(0)
    for s in (1.5, 2.0):
        big = supersampled_camera(cam, s)
        xyz = np.array([[10.0, -20.0, 0.0], [15.0, -15.0, 3.0]])
        sx, sy = big.width / cam.width, big.height / cam.height
        np.testing.assert_allclose(big.project(xyz), (cam.project(xyz) + 0.5) * [sx, sy] - 0.5, atol=1e-9)


@pytest.mark.parametrize('factor', [1.5, 2.0])
def test_supersampled_checkerboard_corners_stay_within_a_tenth_of_a_pixel(factor):
    """Render at factor x size, INTER_AREA down: corners refined by OpenCV sit on the true projections."""
    sim = _sim(lighting=False, effects=False, width=1280, height=720)
    errors = []
    for k in range(len(sim.views)):
        cam = sim.camera(k)
        img, ids = sim.renderer.render(supersampled_camera(cam, factor), None)
        img, _ = downsample(img, ids, cam.width, cam.height)
        gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        for b, board in enumerate(sim.scene.boards):
            _, xyz = board_corners(board, b)
            uv = cam.project(xyz)
            ok = cam.in_image(uv, margin=10)
            if ok.sum() < 50:
                continue
            found = cv2.cornerSubPix(
                gray,
                uv[ok].astype(np.float32).reshape(-1, 1, 2).copy(),
                (3, 3),
                (-1, -1),
                (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 0.001),
            )
            errors.append(np.linalg.norm(found.reshape(-1, 2) - uv[ok], axis=1))
    errors = np.concatenate(errors)
    assert len(errors) > 200
    assert np.median(errors) < 0.1, np.median(errors)


def test_jpeg_round_trip_is_applied_with_the_drones_quality(monkeypatch):
    sim = _sim()
    calls = []
    real = camera_effects.jpeg_round_trip
    monkeypatch.setattr(camera_effects, 'jpeg_round_trip', lambda img, q: calls.append(q) or real(img, q))
    for k in range(3):
        sim.render_view(k)
    assert calls == [effective_jpeg_quality(sim.effects.drones[k].jpeg_quality, 640) for k in range(3)]
    assert all(70 <= sim.effects.drones[k].jpeg_quality <= 95 for k in range(3))
    assert all(90 <= q <= 99 for q in calls)  # 640 px: a 1920-px camera's artefacts seen downsampled
    assert effective_jpeg_quality(60, 1920) == 60


def test_jpeg_round_trip_leaves_block_artefacts():
    rng = np.random.default_rng(0)
    img = cv2.GaussianBlur(rng.integers(0, 255, (64, 64, 3), dtype=np.uint8), (0, 0), 3)
    out = jpeg_round_trip(img, 60)
    assert out.shape == img.shape and out.dtype == np.uint8
    assert 0 < np.abs(out.astype(int) - img).mean() < 10


def test_lighting_ranges_and_dusk():
    cfg = LightingConfig()
    rng = np.random.default_rng(0)
    lights = [sample_lighting(cfg, rng) for _ in range(200)]
    assert all(0.35 <= L.shadow_factor <= 0.85 and L.direction[2] > 0 for L in lights)
    assert all(abs(np.linalg.norm(L.direction) - 1) < 1e-9 for L in lights)
    dusk = sample_lighting(LightingConfig(dusk=[1.0, 1.0]), rng)
    day = sample_lighting(LightingConfig(dusk=[0.0, 0.0]), rng)
    assert sum(dusk.sky) < 0.6 * sum(day.sky)
    # the plain light keeps the plain scene's box shading: 0.55 + 0.45 max(0, n . sun)
    assert np.allclose(DAY.color([100, 100, 100], UP), 100 * (0.55 + 0.45 * DAY.direction[2]))
