"""`matrix-tracker train --site`: one command simulates a site's training and validation sequences (separate
seeds), fine-tunes on the site's BEV grid and writes a checkpoint that records the site, which `evaluate` on
another simulated sequence of the site loads and runs, and which the fuse grid takes only at the site's cell."""

import json

import pytest
import torch

from matrix_core.bev.config import SequenceSpec, TrainConfig
from matrix_core.bev.registry import build_model
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.site_training import finished_simulation, plan_site_training, simulate_settings
from matrix_core.bev.training import load_initial_weights
from matrix_core.cli.main import main
from matrix_core.fusion.fuser import network_grid
from matrix_core.fusion.settings import FuseSettings, shipped_checkpoint
from matrix_core.site import load_site

# a small site at an origin of its own: three drones on the ring, 320 x 180 cameras rendered at half size
COURT = """version: 1
name: court
area: [10.0, -4.0, 18.0, 2.0]
cell_m: 0.25
references: {source: simulate}
drones:
  - name: west
    camera: &cam {image_size: [320, 180], K: [228.5, 0.0, 159.5, 0.0, 228.5, 89.5, 0.0, 0.0, 1.0]}
  - {name: north, camera: *cam}
  - {name: east, camera: *cam}
"""
# the site recipe at a test's size: 160x96 input, one epoch, no weight average
RECIPE = """base: site
bev: {image_width: 160, image_height: 96}
epochs: 1
average_epochs: 0
"""
SMALL = ['--sim-config', 'simple', '--frames', '3', '--val-frames', '2', '--device', 'cpu']


@pytest.fixture(scope='module')
def court(tmp_path_factory):
    folder = tmp_path_factory.mktemp('court')
    (folder / 'court.yaml').write_text(COURT)
    (folder / 'recipe.yaml').write_text(RECIPE)
    return folder


@pytest.fixture(scope='module')
def trained(court):
    """One train --site run (seeds 5 train, 6 validation) fine-tuning the tiny shipped detector."""
    out = court / 'run'
    argv = ['train', '--site', str(court / 'court.yaml'), '--config', str(court / 'recipe.yaml'), '--out', str(out)]
    argv += ['--init', 'detector_tiny_seed0.pt', '--train-seeds', '5', '--val-seeds', '6', *SMALL]
    assert main(argv) == 0
    return argv, out


def test_train_site_writes_a_checkpoint_for_the_site_that_evaluate_runs(court, trained, capsys):
    _, out = trained
    ckpt = torch.load(out / 'detector_court.pt', weights_only=False)
    assert ckpt['site'] == {
        'name': 'court',
        'file': str((court / 'court.yaml').resolve()),
        'area': [10.0, -4.0, 18.0, 2.0],
        'cell_m': 0.25,
        'drones': ['west', 'north', 'east'],
    }
    assert ckpt['settings']['area'] == [10.0, -4.0, 18.0, 2.0] and ckpt['settings']['cell_m'] == 0.25
    assert ckpt['settings']['model'] == 'bev_tiny'  # the init checkpoint's network
    assert 'train seeds [5], validation seeds [6]' in ckpt['trained_with']
    history = json.loads((out / 'history.json').read_text())
    assert [h['epoch'] for h in history] == [1] and 'val_moda[court_val_s6]' in history[0]
    # the simulated sequences, one per seed, of the site's drones
    for name in ('court_train_s5', 'court_val_s6'):
        assert (out / 'data' / name / 'site.yaml').is_file()
    # a held-out seed of the same site, evaluated offline with the new checkpoint
    test = court / 'test_s7'
    sim = ['simulate', '--site', str(court / 'court.yaml'), '--config', 'simple', '--frames', '2', '--seed', '7']
    assert main([*sim, '--image_scale', '0.5', '--out', str(test)]) == 0
    capsys.readouterr()
    ev = court / 'eval'
    argv = ['evaluate', str(test), '--checkpoint', str(out / 'detector_court.pt'), '--out', str(ev), '--heatmaps', '1']
    assert main([*argv, '--device', 'cpu']) == 0
    metrics = json.loads((ev / 'metrics.json').read_text())
    assert metrics['views'] == ['west', 'north', 'east']
    assert metrics['failures']['frames_failed'] == 0 and 'MODA' in capsys.readouterr().out


def test_the_fuse_grid_takes_the_checkpoint_at_the_sites_cell_only(court, trained):
    _, out = trained
    settings = BevSettings(**torch.load(out / 'detector_court.pt', weights_only=False)['settings'])
    grid = network_grid(settings, FuseSettings(views=['west', 'north', 'east'], area=[10.0, -4.0, 18.0, 2.0]))
    assert grid.shape == load_site(court / 'court.yaml').grid_shape(margin_m=settings.margin_m)
    with pytest.raises(ValueError, match='cells of 0.25 m'):
        network_grid(settings, FuseSettings(area=[10.0, -4.0, 18.0, 2.0], cell_m=0.5))


def test_a_second_run_reuses_the_finished_sequences_and_resumes(trained, capsys):
    argv, out = trained
    data = out / 'data' / 'court_train_s5'
    stamp = (data / 'simulate_summary.json').stat().st_mtime_ns
    capsys.readouterr()
    assert main([*argv, '--resume', '--epochs', '2']) == 0
    printed = capsys.readouterr().out
    assert 'train seed 5: reusing' in printed and 'val seed 6: reusing' in printed
    assert (data / 'simulate_summary.json').stat().st_mtime_ns == stamp  # not simulated again
    history = json.loads((out / 'history.json').read_text())
    assert [h['epoch'] for h in history] == [1, 2]
    best = max(history, key=lambda h: h['val_score'])  # printed in percent, as evaluate prints MODA
    assert f'selected: epoch {best["epoch"]}, validation MODA {100 * best["val_score"]:.2f} %' in printed


def test_seeds_shared_by_training_and_validation_are_refused_before_anything_is_written(court, tmp_path):
    argv = ['train', '--site', str(court / 'court.yaml'), '--out', str(tmp_path / 'run')]
    assert main([*argv, '--train-seeds', '1', '2', '--val-seeds', '2', *SMALL]) == 2
    assert main([*argv, '--train-seeds', '--val-seeds', '2', *SMALL]) == 2  # nothing to train on
    assert main(['train', '--site', 'matrix', '--out', str(tmp_path / 'run')]) == 2  # MATRIX has its recipe
    assert not (tmp_path / 'run').exists()


def test_a_dataset_of_another_site_is_refused_naming_it(court, tmp_path, capsys):
    other = tmp_path / 'other.yaml'
    other.write_text(COURT.replace('name: court', 'name: yard').replace('[10.0, -4.0, 18.0, 2.0]', '[0, 0, 8, 6]'))
    data = tmp_path / 'yard_data'
    sim = ['simulate', '--site', str(other), '--config', 'simple', '--frames', '1', '--image_scale', '0.25']
    assert main([*sim, '--out', str(data)]) == 0
    capsys.readouterr()
    argv = ['train', '--site', str(court / 'court.yaml'), '--out', str(tmp_path / 'run'), '--train-data', str(data)]
    assert main([*argv, *SMALL]) == 2
    err = capsys.readouterr().err
    assert f'--train-data {data}: its area [0.0, 0.0, 8.0, 6.0] is not the area' in err and 'court' in err
    assert not (tmp_path / 'run').exists()


def test_an_unfinished_simulation_is_not_taken_for_a_finished_one(court, tmp_path):
    site = load_site(court / 'court.yaml')
    plan = plan_site_training(site, tmp_path, [3], [], 2, 2, 'simple', 0.25)
    settings = simulate_settings(plan, plan.simulated[0])
    assert finished_simulation(settings) is False  # nothing there yet
    folder = plan.simulated[0].folder
    folder.mkdir()
    (folder / 'site.yaml').write_text(COURT)  # what an interrupted run may leave
    with pytest.raises(ValueError, match='holds no finished simulation of seed 3'):
        finished_simulation(settings)


def test_an_init_checkpoint_of_another_network_is_refused():
    config = TrainConfig(
        train=[SequenceSpec('unused')],
        bev=BevSettings(model='bev_small'),
        init=str(shipped_checkpoint('detector_tiny_seed0.pt')),
    )
    with pytest.raises(ValueError, match='network bev_tiny .* but the config trains bev_small'):
        load_initial_weights(build_model('bev_small'), config)
