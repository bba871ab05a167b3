"""Every writing command refuses an output that is, contains or lies inside one of its inputs, and an existing
non-empty output unless --overwrite, before any work: the input folder is byte-for-byte what it was. Files
are written under a temporary name and moved into place when complete, so a failed writer leaves nothing
that looks complete."""

import hashlib
import shutil

import numpy as np
import pytest

from matrix_core.cli.main import main
from matrix_core.metrics import BevPoints, write_bev_points
from matrix_core.output_paths import OutputError, atomic_folder, atomic_path, atomic_write_text, check_output

VIEWS = [f'D{i}' for i in range(1, 9)]


@pytest.fixture
def scratch(matrix_sample, tmp_path):
    """A real copy (no links: a write through one would reach the shared sample) of two frames of the
    sample: images, calibrations, annotations, the reference."""
    data = tmp_path / 'sample'
    for sub in ('calibrations', 'reference', 'annotations_positions'):
        shutil.copytree(matrix_sample / sub, data / sub)
    for view in VIEWS:
        (data / 'image_subsets' / view).mkdir(parents=True)
        for frame in ('0000', '0001'):
            shutil.copy(matrix_sample / 'image_subsets' / view / f'{frame}.jpg', data / 'image_subsets' / view)
    return data


def hashes(folder) -> dict:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.rglob('*') if p.is_file()
    }


def test_calibrate_into_its_own_dataset_is_refused_and_changes_nothing(scratch, capsys):
    before = hashes(scratch)
    assert main(['calibrate', str(scratch), '--out', str(scratch), '--views', 'D1', '--max-frames', '1']) == 2
    assert f'--out {scratch} is the input {scratch}' in capsys.readouterr().err
    assert hashes(scratch) == before


@pytest.mark.parametrize(
    'command',
    [
        ['calibrate', '{data}', '--out', '{data}/calibrated'],
        ['register', '{data}', '--out', '{data}'],
        ['register', '{data}', '--out', '{data}/reference'],
        ['bag', '{data}', '--out', '{data}/bag'],
        ['evaluate', '{data}', '--checkpoint', 'detector_seed1.pt', '--out', '{data}/eval'],
        ['simulate', '--replay', '{data}', '--frames', '1', '--out', '{data}/sim'],
        ['calibrate', '{data}/reference', '--out', '{data}/..'],  # the output contains the input
    ],
    ids=[
        'calibrate-inside',
        'register-same',
        'register-inside',
        'bag-inside',
        'evaluate-inside',
        'simulate-inside',
        'calibrate-contains',
    ],
)
def test_an_output_overlapping_an_input_is_refused_before_any_work(scratch, capsys, command):
    before = hashes(scratch)
    assert main([word.format(data=scratch) for word in command]) == 2
    err = capsys.readouterr().err
    assert 'refusing to write into an input' in err and 'Traceback' not in err
    assert hashes(scratch) == before


def test_an_existing_output_needs_overwrite(tmp_path, capsys):
    dets = tmp_path / 'dets.txt'
    write_bev_points(dets, BevPoints([0, 1], np.array([[1.0, 2.0], [1.1, 2.0]]), scores=[0.9, 0.9]))
    out = tmp_path / 'tracks.txt'
    out.write_text('earlier result\n')
    assert main(['track', str(dets), '--out', str(out)]) == 2
    assert 'exists; --overwrite replaces it' in capsys.readouterr().err
    assert out.read_text() == 'earlier result\n'
    assert main(['track', str(dets), '--out', str(dets), '--overwrite']) == 2  # even with --overwrite: an input
    assert main(['track', str(dets), '--out', str(out), '--overwrite']) == 0
    assert out.read_text() != 'earlier result\n'
    folder = tmp_path / 'reg'
    (folder / 'registration').mkdir(parents=True)
    (folder / 'registration' / 'summary.json').write_text('{}')
    with pytest.raises(OutputError, match='not empty'):
        check_output(folder / 'registration')
    assert check_output(tmp_path / 'new') == tmp_path / 'new'


def test_a_failed_write_leaves_the_old_file_and_no_partial_one(tmp_path):
    path = tmp_path / 'metrics.json'
    atomic_write_text(path, '{"complete": true}')
    with pytest.raises(RuntimeError):
        with atomic_path(path) as tmp:
            tmp.write_text('{"compl')
            raise RuntimeError('killed half way')
    assert path.read_text() == '{"complete": true}' and sorted(p.name for p in tmp_path.iterdir()) == ['metrics.json']
    with pytest.raises(RuntimeError):
        with atomic_folder(tmp_path / 'bag') as partial:
            partial.mkdir()
            (partial / 'bag_0.mcap').write_bytes(b'\x89MCAP0\r\n')
            raise RuntimeError('a bad frame')
    assert sorted(p.name for p in tmp_path.iterdir()) == ['metrics.json']
