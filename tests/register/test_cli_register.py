"""``matrix-tracker register``: JSON per drone and frame, in the MATRIX folder's own file frame."""

import json

import cv2
import numpy as np

from matrix_core.cli.main import main
from matrix_core.datasets.opencv_xml import read_matrices


def _raw_projection(matrix_sample, drone, frame, world_file):
    """The sample README's recipe, independent of our readers: raw image pixels of file-world points."""
    calib = matrix_sample / 'calibrations'
    K = read_matrices(calib / 'intrinsic' / f'intr_Drone{drone}_{frame:04d}.xml', ['camera_matrix'])['camera_matrix']
    ext = read_matrices(calib / 'extrinsic' / f'extr_Drone{drone}_{frame:04d}.xml', ['rvec', 'tvec'])
    uv, _ = cv2.projectPoints(world_file.reshape(-1, 1, 3), ext['rvec'], ext['tvec'], K, None)
    uv = uv.reshape(-1, 2)
    return np.c_[1920.0 - uv[:, 0], uv[:, 1]]


def test_cli_writes_registrations_in_the_file_frame(matrix_sample, tmp_path, capsys):
    assert (
        main(['register', str(matrix_sample), '--out', str(tmp_path), '--views', 'D3', 'D8', '--max-frames', '2']) == 0
    )
    folder = tmp_path / 'registration'
    names = sorted(p.name for p in folder.glob('Drone*.json'))
    assert names == ['Drone3_0000.json', 'Drone3_0001.json', 'Drone8_0000.json', 'Drone8_0001.json']
    for drone, frame in ((3, 0), (8, 1)):
        rec = json.loads((folder / f'Drone{drone}_{frame:04d}.json').read_text())
        assert {
            'H_cur_to_ref',
            'H_img_to_ground',
            'confidence',
            'matches',
            'inliers',
            'status',
            'backend',
            'seconds',
        } <= set(rec)
        assert rec['status'] == 'ok' and rec['backend'] == 'sift' and rec['seconds'] > 0
        # Raw image pixels of known file-world ground points map back to those points.
        gx, gy = np.meshgrid(np.arange(2.0, 29.0, 1.0), np.arange(2.0, 29.0, 1.0))
        world = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
        uv = _raw_projection(matrix_sample, drone, frame, world)
        inside = (uv[:, 0] > 0) & (uv[:, 0] < 1920) & (uv[:, 1] > 0) & (uv[:, 1] < 1080)
        blocked = (np.abs(world[:, 0] - 15) < 2.6) & (np.abs(world[:, 1] - 15) < 2.6)
        uv, world = uv[inside & ~blocked], world[inside & ~blocked]
        H = np.array(rec['H_img_to_ground'])
        hom = np.c_[uv, np.ones(len(uv))] @ H.T
        err = np.linalg.norm(hom[:, :2] / hom[:, 2:] - world[:, :2], axis=1)
        assert len(err) > 50 and np.median(err) < 0.05, f'Drone{drone} frame {frame}: median {np.median(err):.3f} m'
    summary = json.loads((folder / 'summary.json').read_text())
    assert summary['stats']['failed'] == 0 and summary['stats']['error_px_max'] < 1.5
    assert 'registered 4/4 images' in capsys.readouterr().out
    # Overlay pictures: the first frame of each drone by default.
    assert sorted(p.name for p in (folder / 'overlay').glob('*.png')) == ['Drone3_0000.png', 'Drone8_0000.png']


def test_cli_png_writes_every_frame_and_takes_the_scene_from_a_simulated_folder(tmp_path, capsys):
    from matrix_core.sim.sequence import simulate
    from matrix_core.sim.settings import SimulateSettings

    sim = tmp_path / 'sim'
    simulate(SimulateSettings(config='simple', frames=2, seed=1, out=str(sim), fast=True), progress=False)
    assert main(['register', str(sim), '--out', str(tmp_path / 'out'), '--views', 'D2', '--png']) == 0
    out = capsys.readouterr().out
    # The simple variant has no block: nothing to pass on the command line, the folder says so.
    assert '0 obstacle box(es)' in out and 'registered 2/2 images' in out
    assert sorted(p.name for p in (tmp_path / 'out/registration/overlay').glob('*.png')) == [
        'Drone2_0000.png',
        'Drone2_0001.png',
    ]


def test_cli_rejects_unknown_views_and_non_matrix_folders(matrix_sample, tmp_path, capsys):
    assert main(['register', str(matrix_sample), '--out', str(tmp_path), '--views', 'D9']) == 2
    assert 'D9' in capsys.readouterr().err
    assert main(['register', str(tmp_path), '--out', str(tmp_path)]) == 2
    assert main(['register', str(matrix_sample), '--out', str(tmp_path), '--backend', 'nope']) == 2
    assert 'unknown backend' in capsys.readouterr().err
