"""``matrix-tracker track`` and ``matrix-tracker score`` on text files made from the real sample trajectories."""

import json

import numpy as np
import pytest

from matrix_core.cli.main import main
from matrix_core.datasets import open_dataset
from matrix_core.metrics import read_bev_points


@pytest.fixture(scope='module')
def files(matrix_sample, tmp_path_factory):
    """GT "frame id x y" for 60 real time steps and noisy detections "frame x y score" with one empty frame."""
    ds = open_dataset(matrix_sample)
    rng = np.random.default_rng(0)
    out = tmp_path_factory.mktemp('bev')
    gt_lines, det_lines = [], []
    for f in ds.trajectory_frames[:60]:
        for pid, p in sorted(ds.pedestrian_positions(f).items()):
            gt_lines.append(f'{f} {pid} {p[0]:.3f} {p[1]:.3f}')
            if f != 30 and rng.random() > 0.05:
                q = p[:2] + rng.normal(0, 0.08, 2)
                det_lines.append(f'{f} {q[0]:.3f} {q[1]:.3f} {rng.uniform(0.6, 1):.2f}')
    (out / 'gt.txt').write_text('\n'.join(gt_lines) + '\n')
    (out / 'dets.txt').write_text('# frame x y score\n' + '\n'.join(det_lines) + '\n')
    return out


def test_track_then_score(files, capsys):
    assert (
        main(
            [
                'track',
                str(files / 'dets.txt'),
                '--out',
                str(files / 'tracks.txt'),
                '--birth_hits',
                '2',
                '--report_coasting',
                '0',
            ]
        )
        == 0
    )
    tracks = read_bev_points(files / 'tracks.txt')
    assert tracks.has_ids and 30 not in set(tracks.frames)  # nothing reported in the empty frame
    assert 38 <= len(np.unique(tracks.ids)) <= 50
    capsys.readouterr()
    assert main(['score', str(files / 'gt.txt'), str(files / 'tracks.txt'), '--json']) == 0
    report = json.loads(capsys.readouterr().out)
    trk = report['tracking']
    # frame 30 has no detections: its 40 people count as misses (plus births and the 5 % dropped)
    assert trk['fn'] >= 40 and trk['num_gt'] == 60 * 40
    assert trk['mota'] > 0.85 and trk['idf1'] > 0.85
    assert report['detection']['moda'] > 0.85
    hota = report['hota']
    assert 0.5 < hota['hota'] < 1.0 and hota['num_gt'] == trk['num_gt'] and hota['num_pred'] == trk['num_pred']
    assert main(['score', str(files / 'gt.txt'), str(files / 'tracks.txt')]) == 0
    text = capsys.readouterr().out
    assert f"{100 * hota['hota']:6.2f} %" in text.split('HOTA (@1 m)')[1].splitlines()[0]


def test_score_detections_only_and_table(files, capsys):
    assert main(['score', str(files / 'gt.txt'), str(files / 'dets.txt')]) == 0
    text = capsys.readouterr().out
    assert 'MODA (@0.5 m)' in text and 'MOTA' not in text and 'HOTA' not in text
    moda = float(text.split('MODA (@0.5 m)')[1].split('%')[0])
    assert 90 < moda < 96  # about 5 % dropped + one empty frame of 60


def test_bad_file_is_a_clear_error(tmp_path, capsys):
    (tmp_path / 'bad.txt').write_text('0 1 2 x\n')
    assert main(['score', str(tmp_path / 'bad.txt'), str(tmp_path / 'bad.txt')]) == 2
    assert 'bad.txt:1' in capsys.readouterr().err
    assert main(['track', str(tmp_path / 'missing.txt'), '--out', str(tmp_path / 'o.txt')]) == 2
