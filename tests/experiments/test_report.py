"""RESULTS.md from hand-made metrics.json files: our numbers in the tables, the paper's beside them."""

import dataclasses
import json

import pytest

from matrix_core.experiments import paper
from matrix_core.experiments.report import write_report
from matrix_core.experiments.sizes import FULL, MEDIUM, QUICK

PNG = b'\x89PNG\r\n\x1a\n'


def record(model, test, moda, mota=0.5, calibration='ground_truth', dropped=(), rate=0.0, seed=-1):
    det = {'moda': moda, 'modp': 0.75, 'precision': 0.9, 'recall': 0.85, 'mean_error_m': 0.12, 'tp': 85, 'fp': 9,
           'fn': 15, 'num_gt': 100, 'num_frames': 10, 'threshold': 0.5}
    trk = {'mota': mota, 'motp_m': 0.2, 'motp_percent': 80.0, 'idf1': 0.6, 'idp': 0.6, 'idr': 0.6, 'precision': 0.9,
           'recall': 0.85, 'mostly_tracked': 7, 'partially_tracked': 2, 'mostly_lost': 1, 'num_gt_ids': 10,
           'id_switches': 3, 'fragmentations': 2, 'fp': 9, 'fn': 15, 'matches': 85, 'num_gt': 100, 'num_pred': 94,
           'num_frames': 10, 'gate': 1.0}
    views = [v for v in ('D1', 'D2', 'D3', 'D4', 'D5', 'D6', 'D7', 'D8') if v not in dropped]
    return {'model': model, 'test': test, 'calibration': calibration, 'dropped': list(dropped), 'drop_rate': rate,
            'drop_seed': seed, 'views': views if dropped else None, 'views_used': views,
            'trained': {'frames': [0, QUICK.transfer_frames - 1]}, 'detection': det, 'tracking': trk}


def write_run(run_dir, size, records, steps):
    for i, r in enumerate(records):
        path = run_dir / 'eval' / f'{i:03d}_{r["model"]}' / 'metrics.json'
        path.parent.mkdir(parents=True)
        path.write_text(json.dumps(r))
    machine = {'cpu': 'Test CPU 9000', 'cpu_count': 2, 'threads': 1, 'torch': '9.9', 'python': '3.11',
               'platform': 'linux', 'git_commit': 'abc123'}
    (run_dir / 'run.json').write_text(json.dumps({
        'size': {**dataclasses.asdict(size), 'transfer_frames': size.transfer_frames}, 'machine': machine,
        'started_utc': 'now', 'wall_s': 123.0, 'steps': steps}))


def row(text, start):
    lines = [line for line in text.splitlines() if line.startswith(start)]
    assert len(lines) == 1, (start, lines)
    return lines[0]


@pytest.fixture
def hand_made(tmp_path):
    records = [record('simple_s0', 'simple', 0.9321, 0.9012), record('complex_s0', 'complex', 0.8123, 0.7654),
               record('complex_s1', 'complex', 0.7123), record('complex_s2', 'complex', 0.6123),
               record('complex_s0', 'complex', 0.1111, calibration='frozen_first'),
               record('complex_s0', 'complex', 0.2222, calibration='reference'),
               record('complex_s0', 'complex', 0.7777, calibration='pnp'),
               record('complex_static', 'complex', 0.0333, 0.0444, calibration='frozen_first'),
               record('modified_scratch', 'modified', 0.4111), record('modified_transfer', 'modified', 0.5222),
               record('complex_s0', 'modified', 0.3333)]
    records += [record('complex_s0', 'complex', m, dropped=('D1', 'D5'), rate=0.25, seed=s)
                for s, m in enumerate((0.70, 0.72, 0.74))]
    records += [record('complex_s0', 'complex', m, dropped=('D1', 'D2', 'D3', 'D5', 'D6', 'D8'), rate=0.75, seed=s)
                for s, m in enumerate((0.30, 0.40, 0.50))]
    steps = {'eval/x': {'state': 'done', 'wall_s': 1.0},
             'eval/complex_s0__complex__registration': {'state': 'unavailable', 'reason': 'no source XYZ here'}}
    return tmp_path, records, steps


@pytest.mark.parametrize('size', [QUICK, MEDIUM, FULL], ids=['quick', 'medium', 'full'])
def test_report_tables_hold_the_given_numbers_and_the_papers(hand_made, size):
    tmp_path, records, steps = hand_made
    write_run(tmp_path / 'run', size, records, steps)
    path = write_report(tmp_path / 'run', tmp_path / 'docs' / 'RESULTS.md')
    text = path.read_text()
    assert ('SMOKE-TEST NUMBERS' in text) == size.smoke_test
    assert ('REDUCED-SIZE RUN' in text) == (size is MEDIUM)
    # 1: simple and complex with all metrics, the paper's proposed method beside.
    assert '| 93.2 | 75.0 | 90.0 | 85.0 | 90.1 | 80.0 | 60.0 | 70.0 | 10.0 |' in row(text, '| ours, simple |')
    assert '| 81.2 |' in row(text, '| ours, complex |') and '| 76.5 |' in row(text, '| ours, complex |')
    assert f'| {paper.PROPOSED_COMPLEX["moda"]:.1f} |' in row(text, '| paper, proposed, complex |')
    # 2: sources, static-trained model, the paper's numbers; a source that did not run says why.
    ours = row(text, '| `complex_s0` | `ground_truth`')
    assert '| 81.2 |' in ours and '89.0 / 88.5' in ours
    assert '| 77.8 |' in row(text, '| `complex_s0` | `pnp`')
    assert '| 11.1 |' in row(text, '| `complex_s0` | `frozen_first`')
    assert '| 22.2 |' in row(text, '| `complex_s0` | `reference`')
    assert '| n/a |' in row(text, '| `complex_s0` | `registration`')
    static = row(text, '| `complex_static`')
    assert '| 3.3 |' in static and '| 4.4 |' in static and 'TrackTacular: 5.7 / 31.0' in static
    assert 'no source XYZ here' in text and '**unavailable**' in text
    # 3: transfer against the paper's 54 -> 69.
    assert '| 41.1 |' in row(text, '| from scratch |') and '| 54.0 |' in row(text, '| from scratch |')
    assert '| 52.2 |' in row(text, '| initialised with') and '| 69.0 |' in row(text, '| initialised with')
    assert '| 33.3 |' in row(text, '| `complex_s0` without fine-tuning |')
    # 4: mean +- std over the subsets, with the paper's dropout figures.
    assert '| 72.0 ± 2.0 |' in row(text, '| complex | 0.25 |') and 'MODA > 80' in row(text, '| complex | 0.25 |')
    assert '| 40.0 ± 10.0 |' in row(text, '| complex | 0.75 |') and '~45 % / ~36 %' in row(text, '| complex | 0.75 |')
    assert '| 2 | 3 |' in row(text, '| complex | 0.75 |')            # 2 views kept, 3 subsets
    # 5: seeds and their mean +- std.
    assert '**71.2 ± 10.0**' in row(text, '| **mean ± std** |')
    # settings and machine.
    assert 'Test CPU 9000' in text and 'abc123' in text and f'{size.image_width}x{size.image_height}' in text
    images = tmp_path / 'docs' / 'images' / 'results'
    for name in ('exp1_simple_vs_complex.png', 'exp2_static_baselines.png', 'exp3_transfer.png', 'exp4_dropout.png'):
        assert (images / name).read_bytes()[:8] == PNG
        assert f'](images/results/{name})' in text


def test_report_needs_a_run(tmp_path):
    with pytest.raises(FileNotFoundError, match='run.json'):
        write_report(tmp_path, tmp_path / 'RESULTS.md')


def test_report_lists_evaluations_with_failed_frames(hand_made):
    """An evaluation step whose frames partly failed (issue 17) is listed with its counts."""
    tmp_path, records, steps = hand_made
    records[1] = {**records[1], 'num_frames': 10, 'failures': {'frames_failed': 2, 'frames_scored': 8,
                                                               'views_masked': 3}}
    write_run(tmp_path / 'run', QUICK, records, steps)
    text = write_report(tmp_path / 'run', tmp_path / 'docs' / 'RESULTS.md').read_text()
    assert '## Evaluations with failed frames or masked views' in text
    assert 'complex_s0 on complex (ground_truth, views' in text and '2 of 10 frames failed, 3 views masked' in text
