"""Drone and crowd motion match the real MATRIX sample statistics (README of shared/matrix_sample)."""

import numpy as np

from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.sim.config import load_scene_config
from matrix_core.sim.crowd import Crowd
from matrix_core.sim.drones import DroneFleet


def test_drone_motion_matches_real_statistics():
    cfg = load_scene_config('complex')
    fleet = DroneFleet(cfg.drones, cfg.center, np.random.default_rng(4))
    cams = []
    for _ in range(120):
        fleet.step(0.5)
        cams.append([fleet.camera(k, 640, 360) for k in range(8)])
    centers = np.array([[c.center for c in frame] for frame in cams])
    speed = np.linalg.norm(np.diff(centers, axis=0), axis=2) / 0.5
    rot = [rotation_angle_deg(a.R, b.R) for f0, f1 in zip(cams, cams[1:]) for a, b in zip(f0, f1)]
    tilt = np.array([[c.tilt_deg for c in frame] for frame in cams])
    print(
        f'speed median {np.median(speed):.2f} m/s, rotation median {np.median(rot):.1f} deg/step, '
        f'tilt {tilt.min():.0f}..{tilt.max():.0f} deg, '
        f'height {centers[..., 2].min():.2f}..{centers[..., 2].max():.2f} m'
    )
    assert 0.4 <= np.median(speed) <= 0.9 and speed.max() <= 1.5 + 1e-6
    assert 1.5 <= np.median(rot) <= 7.0
    assert 10.0 <= tilt.min() and tilt.max() <= 50.0
    assert 11.3 <= centers[..., 2].min() and centers[..., 2].max() <= 13.3


def test_crowd_walks_like_matrix_pedestrians():
    cfg = load_scene_config('complex')
    crowd = Crowd(cfg, np.random.default_rng(2))
    track = [crowd.positions.copy()]
    for _ in range(80):
        crowd.step(0.5)
        track.append(crowd.positions.copy())
    track = np.array(track)
    step = np.linalg.norm(np.diff(track, axis=0), axis=2)[2:]
    print(f'step median {np.median(step):.2f} m, p95 {np.percentile(step, 95):.2f} m, max {step.max():.2f} m')
    assert 0.5 <= np.median(step) <= 0.7 and step.max() < 1.0
    x0, y0, x1, y1 = cfg.block.bounds
    inside_block = (track[..., 0] > x0) & (track[..., 0] < x1) & (track[..., 1] > y0) & (track[..., 1] < y1)
    assert not inside_block.any()
    ax0, ay0, ax1, ay1 = cfg.area
    assert track[..., 0].min() >= ax0 and track[..., 0].max() <= ax1
    assert track[..., 1].min() >= ay0 and track[..., 1].max() <= ay1
    gaps = np.linalg.norm(track[:, :, None] - track[:, None], axis=3) + np.eye(track.shape[1]) * 99
    nearest = np.percentile(gaps.min(axis=2), [1, 5])
    print(f'nearest neighbour p1 {nearest[0]:.2f} m, p5 {nearest[1]:.2f} m')
    # people keep the real crowd's distance (real sample: 1.00 / 1.09 m, scripts/crowd_stats.py) and never merge
    assert nearest[0] > 0.9 and 0.95 < nearest[1] < 1.25


def test_reference_poses_match_real_reference_calibrations(matrix_sample):
    """The simulated static reference cameras sit where the real sample's reference drones are and look
    the same way (real ones aim within ~4 deg of the centre)."""
    from matrix_core.datasets import open_dataset

    real = open_dataset(matrix_sample)
    cfg = load_scene_config('complex')
    fleet = DroneFleet(cfg.drones, cfg.center, np.random.default_rng(0))
    for k, view in enumerate(real.views):
        ours, theirs = fleet.reference_camera(k, 1920, 1080), real.reference_camera(view)
        assert np.linalg.norm(ours.center - theirs.center) < 0.3, view
        assert rotation_angle_deg(ours.R, theirs.R) < 6.0, view
        assert np.allclose(ours.K, theirs.K, atol=0.05), view


def test_drone_poses_cover_real_frame_poses(matrix_sample):
    """Heights and distances of the real frames 0000-0004 fall within the simulated ranges."""
    from matrix_core.datasets import open_dataset

    real = open_dataset(matrix_sample)
    real_c = np.array([real.camera(v, f).center for v in real.views for f in real.frames])
    cfg = load_scene_config('complex')
    fleet = DroneFleet(cfg.drones, cfg.center, np.random.default_rng(1))
    sim_c = []
    for _ in range(200):
        fleet.step(0.5)
        sim_c += [fleet.camera(k, 640, 360).center for k in range(8)]
    sim_c = np.array(sim_c)
    center = np.array([*cfg.center, 0.0])
    real_d, sim_d = (np.linalg.norm(c[:, :2] - center[:2], axis=1) for c in (real_c, sim_c))
    assert sim_d.min() <= real_d.min() + 1.0 and sim_d.max() >= real_d.max() - 1.0
    assert sim_c[:, 2].min() <= real_c[:, 2].min() + 0.5 and sim_c[:, 2].max() >= real_c[:, 2].max() - 0.5
