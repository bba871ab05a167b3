"""``--site`` of ``bag``, ``evaluate`` and ``evaluate-recording``: data of the site passes, data of another
site is an error naming what differs before any work, and a site dataset's boxes score in the image plane."""

import json

import pytest

from matrix_core.cli.main import main
from matrix_core.datasets import open_dataset
from matrix_core.evaluation.image_plane import annotated_boxes
from matrix_core.evaluation.recording import ground_truth_from_bag
from matrix_core.metrics import write_bev_points


@pytest.fixture(scope='module')
def ring3(tmp_path_factory):
    out = tmp_path_factory.mktemp('ring3') / 'data'
    argv = ['simulate', '--site', 'ring3', '--config', 'simple', '--frames', '2', '--image_scale', '0.25']
    assert main([*argv, '--bag', '--out', str(out)]) == 0
    return out


def test_bag_site_agrees_or_is_refused(ring3, tmp_path, capsys):
    assert main(['bag', str(ring3), '--site', 'ring3', '--out', str(tmp_path / 'ok')]) == 0
    capsys.readouterr()
    assert main(['bag', str(ring3), '--site', 'plaza', '--out', str(tmp_path / 'no')]) == 2
    err = capsys.readouterr().err
    assert 'its area [-15.0, -10.0, 15.0, 10.0] is not the area [-24.0, -12.0, 24.0, 12.0]' in err
    assert "its drones ['north', 'southwest', 'southeast'] are not drones" in err and 'Traceback' not in err
    assert not (tmp_path / 'no').exists()


def test_evaluate_recording_site_and_site_dataset_boxes(ring3, tmp_path, capsys):
    bag = ring3 / 'bag'
    write_bev_points(tmp_path / 'tracks.txt', ground_truth_from_bag(bag))
    out = tmp_path / 'm.json'
    argv = ['evaluate-recording', str(tmp_path / 'tracks.txt'), '--ground-truth', str(bag), '--json', str(out)]
    assert main([*argv, '--site', 'ring3']) == 0
    assert json.loads(out.read_text())['detection']['moda'] == 1.0
    capsys.readouterr()
    assert main([*argv, '--site', 'plaza', '--overwrite']) == 2
    assert 'names drones north, southeast, southwest, which site plaza' in capsys.readouterr().err
    # the annotated boxes of a site dataset, clipped to each drone's own image
    dataset = open_dataset(ring3)
    gt = annotated_boxes(dataset, list(dataset.frames), list(dataset.views))
    assert len(gt) > 0 and set(gt.views.tolist()) <= set(dataset.views)


def test_evaluate_site_mismatch_is_refused_before_work(ring3, tmp_path, capsys):
    argv = ['evaluate', str(ring3), '--checkpoint', 'detector_tiny_seed0.pt', '--device', 'cpu', '--heatmaps', '1']
    assert main([*argv, '--site', 'plaza', '--out', str(tmp_path / 'no')]) == 2
    assert 'of site plaza' in capsys.readouterr().err and not (tmp_path / 'no').exists()
    assert main([*argv, '--site', 'ring3', '--out', str(tmp_path / 'ok')]) == 0
    assert json.loads((tmp_path / 'ok' / 'metrics.json').read_text())['site'] == 'ring3'
