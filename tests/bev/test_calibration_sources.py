"""The pnp and registration calibration sources on a small simulated sequence: their homographies match the
ground truth, and views without a result (PnP failed, registration failed) are masked, never invented."""

import csv
import json

import numpy as np
import pytest

from matrix_core.bev.calibration_sources import calibration_source
from matrix_core.bev.data import BevFrames
from matrix_core.bev.settings import BevSettings
from matrix_core.calib.scene import default_config_path
from matrix_core.cli.main import main
from matrix_core.datasets import open_dataset
from matrix_core.fusion.settings import shipped_checkpoint

SETTINGS = BevSettings(image_width=160, image_height=96, cell_m=0.5)


@pytest.fixture(scope='module')
def sequence(tmp_path_factory):
    """4 simulated complex frames at 1920x1080 (the calibration config's size) with calibrate + register."""
    root = tmp_path_factory.mktemp('sources')
    data, pnp, reg = root / 'data', root / 'pnp', root / 'reg'
    assert (
        main(
            [
                'simulate',
                '--config',
                'complex',
                '--frames',
                '4',
                '--seed',
                '5',
                '--out',
                str(data),
                '--image_ext',
                '.jpg',
            ]
        )
        == 0
    )
    assert (
        main(['calibrate', str(data), '--out', str(pnp), '--config', str(default_config_path('sim_complex.yaml'))]) == 0
    )
    assert main(['register', str(data), '--out', str(reg)]) == 0
    return data, pnp, reg


def pixel_errors(dataset, homography_of, view, frame) -> np.ndarray:
    """Distances (full-resolution px) between the source's and the true projections of ground points the
    true camera sees."""
    cam = dataset.camera(view, frame)
    x0, y0, x1, y1 = dataset.area
    xs, ys = np.meshgrid(np.linspace(x0, x1, 31), np.linspace(y0, y1, 31))
    ground = np.stack([xs.ravel(), ys.ravel(), np.ones(xs.size)], 1)

    def project(H):
        p = ground @ H.T
        return p[:, :2] / p[:, 2:], p[:, 2]

    true_uv, depth = project(cam.img_H_ground())
    inside = (
        (depth > 0)
        & (true_uv[:, 0] >= 0)
        & (true_uv[:, 0] < cam.width)
        & (true_uv[:, 1] >= 0)
        & (true_uv[:, 1] < cam.height)
    )
    H, size = homography_of(view, frame)
    assert size == (cam.width, cam.height)
    uv, _ = project(H)
    return np.linalg.norm(uv - true_uv, axis=1)[inside]


@pytest.mark.slow
def test_pnp_source_matches_ground_truth_and_masks_failures(sequence):
    data, pnp, _ = sequence
    dataset = open_dataset(data)
    with open(pnp / 'calibration_status.csv', newline='') as fh:
        status = {(r['view'], int(r['frame'])): r['status'] for r in csv.DictReader(fh)}
    source = calibration_source('pnp', dataset, dataset.frames, pnp)
    ok = [k for k, s in status.items() if s == 'ok']
    assert len(ok) >= 16, status
    errors = np.concatenate([pixel_errors(dataset, source, v, f) for v, f in ok])
    print(f'pnp: {len(ok)}/{len(status)} views ok, error median {np.median(errors):.2f} px, max {errors.max():.2f} px')
    assert np.median(errors) < 1.0 and errors.max() < 5.0
    for (v, f), s in status.items():
        assert (source(v, f) is None) == (s != 'ok')
    # the masks reach the network inputs
    frames = BevFrames(data, SETTINGS, calibration='pnp', calibration_dir=pnp, cache_images=False)
    for f in dataset.frames:
        x = frames.inputs(f)
        expected = [status[(v, f)] == 'ok' for v in dataset.views]
        assert x['view_mask'].tolist() == expected
        assert float(x['images'][~x['view_mask']].abs().sum()) == 0.0
    with pytest.raises(ValueError, match='calibration_dir'):
        BevFrames(data, SETTINGS, calibration='pnp')


@pytest.mark.slow
def test_registration_source_matches_ground_truth_and_masks_failures(sequence, tmp_path):
    data, _, reg = sequence
    dataset = open_dataset(data)
    source = calibration_source('registration', dataset, dataset.frames, reg)
    errors = np.concatenate([pixel_errors(dataset, source, v, f) for v in dataset.views for f in dataset.frames])
    print(f'registration: error median {np.median(errors):.2f} px, max {errors.max():.2f} px')
    assert np.median(errors) < 2.0 and errors.max() < 15.0
    # a failed record, as register writes it: status failed, null matrices -> the view is masked
    failed = tmp_path / 'reg'
    (failed / 'registration').mkdir(parents=True)
    for p in (reg / 'registration').glob('Drone*.json'):
        (failed / 'registration' / p.name).write_text(p.read_text())
    record = json.loads((reg / 'registration' / 'Drone3_0002.json').read_text())
    record.update(status='failed', H_cur_to_ref=None, H_img_to_ground=None, message='too few inliers')
    (failed / 'registration' / 'Drone3_0002.json').write_text(json.dumps(record))
    (failed / 'registration' / 'Drone5_0001.json').unlink()
    frames = BevFrames(data, SETTINGS, calibration='registration', calibration_dir=failed, cache_images=False)
    assert frames.inputs(2)['view_mask'].tolist() == [v != 'D3' for v in dataset.views]
    assert frames.inputs(1)['view_mask'].tolist() == [v != 'D5' for v in dataset.views]
    assert all(frames.inputs(0)['view_mask'].tolist())
    # where registration succeeded, the lifted grid agrees with the ground truth one
    gt = BevFrames(data, SETTINGS, cache_images=False)
    centre = np.array([gt.grid.nx / 2, gt.grid.ny / 2, 1.0])
    uv = lambda H: (H @ centre)[:, :2] / (H @ centre)[:, 2:]
    assert np.linalg.norm(uv(gt.homographies(0)) - uv(frames.homographies(0)), axis=1).max() < 1.0


@pytest.mark.slow
def test_evaluate_cli_takes_a_calibration_dir(sequence, tmp_path, capsys):
    data, pnp, _ = sequence
    ckpt = shipped_checkpoint()
    assert (
        main(
            [
                'evaluate',
                str(data),
                '--checkpoint',
                str(ckpt),
                '--calibration',
                'pnp',
                '--calibration-dir',
                str(pnp),
                '--out',
                str(tmp_path),
                '--heatmaps',
                '1',
            ]
        )
        == 0
    )
    metrics = json.loads((tmp_path / 'metrics.json').read_text())
    assert metrics['calibration'] == 'pnp' and metrics['calibration_dir'] == str(pnp)
    assert metrics['detection']['num_gt'] > 0 and 'MODA' in capsys.readouterr().out
