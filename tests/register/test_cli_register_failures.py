"""``matrix-tracker register`` finishes the batch when single frames or drones fail, and counts them."""

import json

import matrix_core.cli.register as register_cli
from matrix_core.cli.main import main
from matrix_core.datasets import DatasetError, MatrixDataset


def test_frames_that_raise_are_reported_and_the_run_finishes(matrix_sample, tmp_path, monkeypatch, capsys):
    measure = register_cli.homography_error_px
    calls = []

    def flaky_measure(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:  # D3 frame 1, as the real run's drone 8 frame did
            raise ValueError('no ground point of the area is visible in the current image')
        return measure(*args, **kwargs)

    load = MatrixDataset.load_image

    def flaky_load(self, view, frame):
        if (view, frame) == ('D8', 0):
            raise DatasetError('cannot decode image D8/0000.jpg')
        return load(self, view, frame)

    monkeypatch.setattr(register_cli, 'homography_error_px', flaky_measure)
    monkeypatch.setattr(MatrixDataset, 'load_image', flaky_load)
    assert (
        main(['register', str(matrix_sample), '--out', str(tmp_path), '--views', 'D3', 'D8', '--max-frames', '2']) == 0
    )
    folder = tmp_path / 'registration'
    summary = json.loads((folder / 'summary.json').read_text())
    stats, pairs = summary['stats'], {(p['view'], p['frame']): p for p in summary['pairs']}
    assert stats['pairs'] == 4 and stats['failed'] == 1 and stats['raised'] == 2 and stats['unmeasured'] == 1
    # The registration of D3 frame 1 stands; only its check against the calibration is missing, with why.
    assert pairs['D3', 1]['status'] == 'ok' and pairs['D3', 1]['error_px'] is None
    assert pairs['D3', 1]['failure'] == (
        'error vs calibration: ValueError: no ground point of the area is visible in the current image'
    )
    assert pairs['D8', 0]['status'] == 'failed' and 'cannot decode image' in pairs['D8', 0]['failure']
    assert pairs['D3', 0]['error_px'] < 1.5 and pairs['D8', 1]['error_px'] < 1.5  # the others are untouched
    rec = json.loads((folder / 'Drone8_0000.json').read_text())
    assert rec['status'] == 'failed' and rec['H_cur_to_ref'] is None and 'cannot decode' in rec['message']
    captured = capsys.readouterr()
    assert 'registered 3/4 images' in captured.out and '2 frame(s) raised' in captured.out
    assert 'D8 frame 0: register: DatasetError' in captured.err + captured.out


def test_a_drone_whose_reference_fails_does_not_stop_the_others(matrix_sample, tmp_path, monkeypatch):
    reference = register_cli._reference

    def flaky_reference(dataset, view):
        if view == 'D3':
            raise ValueError('D3/reference: no reference feature lies on the ground (check the calibration)')
        return reference(dataset, view)

    monkeypatch.setattr(register_cli, '_reference', flaky_reference)
    assert (
        main(['register', str(matrix_sample), '--out', str(tmp_path), '--views', 'D3', 'D8', '--max-frames', '1']) == 0
    )
    summary = json.loads((tmp_path / 'registration' / 'summary.json').read_text())
    assert summary['stats']['failed'] == 1 and summary['stats']['raised'] == 1
    d3, d8 = summary['pairs']
    assert d3['status'] == 'failed' and d3['failure'].startswith('reference: ValueError: D3/reference')
    assert d8['status'] == 'ok' and d8['error_px'] < 1.5
