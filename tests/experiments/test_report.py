"""RESULTS.md from hand-made metrics.json files: our numbers in the tables, the paper's beside them."""

import dataclasses
import json
import subprocess

import pytest

from matrix_core.experiments.plan import transfer_name
from matrix_core.experiments.report import write_report
from matrix_core.experiments.sizes import FULL, MEDIUM, QUICK, STANDARD

PNG = b'\x89PNG\r\n\x1a\n'


def record(
    model,
    test,
    moda,
    mota=0.5,
    calibration='ground_truth',
    dropped=(),
    rate=0.0,
    seed=-1,
    ransac_seed=None,
    frames=QUICK.transfer_frames,
    hota=0.55,
):
    det = {
        'moda': moda,
        'modp': 0.75,
        'precision': 0.9,
        'recall': 0.85,
        'mean_error_m': 0.12,
        'tp': 85,
        'fp': 9,
        'fn': 15,
        'num_gt': 100,
        'num_frames': 10,
        'threshold': 0.5,
    }
    trk = {
        'mota': mota,
        'motp_m': 0.2,
        'motp_percent': 80.0,
        'idf1': 0.6,
        'idp': 0.6,
        'idr': 0.6,
        'precision': 0.9,
        'recall': 0.85,
        'mostly_tracked': 7,
        'partially_tracked': 2,
        'mostly_lost': 1,
        'num_gt_ids': 10,
        'id_switches': 3,
        'fragmentations': 2,
        'fp': 9,
        'fn': 15,
        'matches': 85,
        'num_gt': 100,
        'num_pred': 94,
        'num_frames': 10,
        'gate': 1.0,
    }
    views = [v for v in ('D1', 'D2', 'D3', 'D4', 'D5', 'D6', 'D7', 'D8') if v not in dropped]
    return {
        'model': model,
        'test': test,
        'calibration': calibration,
        'ransac_seed': ransac_seed,
        'dropped': list(dropped),
        'drop_rate': rate,
        'drop_seed': seed,
        'views': views if dropped else None,
        'views_used': views,
        'trained': {'frames': [0, frames - 1]},
        'detection': det,
        'tracking': trk,
        # a record written before evaluations reported HOTA has none (its HOTA cells read n/a)
        **({} if hota is None else {'hota': {'hota': hota, 'det_a': 0.65, 'ass_a': hota**2 / 0.65, 'gate': 1.0}}),
    }


def write_run(run_dir, size, records, steps, done=None, table=None, real=None):
    for i, r in enumerate(records):
        path = run_dir / 'eval' / f'{i:03d}_{r["model"]}' / 'metrics.json'
        path.parent.mkdir(parents=True)
        path.write_text(json.dumps(r))
    for name, rec in (done or {}).items():
        path = run_dir / 'steps' / f'{name}.done.json'
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(rec))
    if table is not None:
        (run_dir / 'tables' / 'multiviewx_sample').mkdir(parents=True)
        (run_dir / 'tables' / 'multiviewx_sample' / 'metrics.json').write_text(json.dumps(table))
    if real is not None:
        (run_dir / 'tables' / 'matrix_sample_live').mkdir(parents=True)
        (run_dir / 'tables' / 'matrix_sample_live' / 'metrics.json').write_text(json.dumps(real))
    machine = {
        'cpu': 'Test CPU 9000',
        'cpu_count': 2,
        'threads': 1,
        'torch': '9.9',
        'python': '3.11',
        'platform': 'linux',
        'git_commit': 'abc123',
        'jobs': 2,
    }
    (run_dir / 'run.json').write_text(
        json.dumps(
            {
                'size': {
                    **dataclasses.asdict(size),
                    'transfer_fraction': size.transfer_fraction,
                    'transfer_frames': size.transfer_frames,
                },
                'machine': machine,
                'started_utc': 'now',
                'wall_s': 123.0,
                'steps': steps,
            }
        )
    )


def row(text, start):
    lines = [line for line in text.splitlines() if line.startswith(start)]
    assert len(lines) == 1, (start, lines)
    return lines[0]


def section(text, title):
    """The text of one '## ' or '### ' section (up to the next heading of its level or above)."""
    start = text.index(title)
    ends = [e for e in (text.find(f'\n{h} ', start + 1) for h in ('##', '###')[: title.count('#') - 1]) if e > 0]
    return text[start : min(ends) if ends else None]


def variant_rows(size):
    records = []
    for variant, model, base in (('simple', 'simple_s0', 0.90), ('complex', 'complex_s0', 0.80)):
        for i, source in enumerate(('registration', 'pnp', 'pnp_stale', 'ground_truth', 'frozen_first', 'reference')):
            old = variant == 'simple' and source == 'ground_truth'
            records.append(record(model, variant, base - 0.01 * i, calibration=source, hota=None if old else 0.55))
        records.append(record(f'{variant}_static', variant, 0.0333, 0.0444, calibration='frozen_first'))
    records += [
        record(f'complex_s{s}', 'complex', m, calibration='registration')
        for s, m in zip(size.seeds[1:], (0.7123, 0.6123))
    ]
    records += [
        record('complex_s0', 'complex', 0.60 + 0.02 * k, calibration='registration', ransac_seed=k)
        for k in size.ransac_seeds
    ]
    for share in size.transfer_shares:
        frames = size.frames_of_share(share)
        records.append(record(transfer_name('scratch', share), 'modified', 0.30 + share / 2, frames=frames))
        records.append(record(transfer_name('transfer', share), 'modified', 0.45 + share / 4, frames=frames))
    records.append(record('complex_s0', 'modified', 0.3333))
    records += [
        record('complex_s0', 'complex', m, dropped=('D1', 'D5'), rate=0.25, seed=s)
        for s, m in enumerate((0.70, 0.72, 0.74))
    ]
    records += [
        record('complex_s0', 'complex', m, dropped=('D1', 'D2', 'D3', 'D5', 'D6', 'D8'), rate=0.75, seed=s)
        for s, m in enumerate((0.30, 0.40, 0.50))
    ]
    return records


TABLE = {
    'dataset': 'shared:multiviewx_sample',
    'format': 'MultiviewXDataset',
    'frames': 10,
    'views': {'C1': {'n': 200, 'median_px': 3.14, 'p90_px': 9.87, 'camera_height_m': 2.5, 'tilt_deg': 10.1}},
}


@pytest.mark.parametrize('size', [QUICK, MEDIUM, STANDARD, FULL], ids=['quick', 'medium', 'standard', 'full'])
def test_report_tables_hold_the_given_numbers_and_the_papers(tmp_path, size):
    steps = {
        'eval/x': {'state': 'done', 'wall_s': 1.0},
        'eval/simple_s0__simple__pnp': {'state': 'unavailable', 'reason': 'no source XYZ here'},
    }
    records = [r for r in variant_rows(size) if not (r['model'] == 'simple_s0' and r['calibration'] == 'pnp')]
    real = {
        **record('detector_seed1.pt', 'real', 0.99, mota=0.925),
        'checkpoint': 'detector_seed1.pt',
        'checkpoint_sha256': 'ab' * 32,
        'dataset': 'shared:matrix_sample',
    }
    write_run(tmp_path / 'run', size, records, steps, table=TABLE, real=real)
    path = write_report(tmp_path / 'run', tmp_path / 'docs' / 'RESULTS.md', repo=tmp_path)
    text = path.read_text()
    assert ('SMOKE-TEST NUMBERS' in text) == size.smoke_test
    assert ('REDUCED-SIZE RUN' in text) == (size is MEDIUM) and ('STANDARD-SIZE RUN' in text) == (size is STANDARD)
    # 1: per variant, the live pipeline first, PnP beside it, the oracle and static rows labelled, paper rows.
    simple, complex_ = section(text, '### Simple variant'), section(text, '### Complex variant')
    live = row(simple, '| **ours, live pipeline** (registration homographies) |')
    assert live.endswith(
        '| `registration` | 90.0 | 75.0 | 90.0 | 85.0 | 50.0 | 80.0 | 60.0 | 70.0 | 10.0 | 55.0 | 65.0 | 46.5 |'
    )
    assert row(simple, '| oracle geometry').endswith('| 70.0 | 10.0 | n/a | n/a | n/a |')  # written without HOTA
    assert '| n/a |' in row(simple, '| ours, PnP route |') and 'no source XYZ here' in text
    assert '| 87.0 |' in row(simple, '| oracle geometry (simulator calibration) |')
    assert '| 80.0 |' in row(complex_, '| **ours, live pipeline**')
    assert '| 79.0 |' in row(complex_, '| ours, PnP route |')
    assert '| 78.0 |' in row(complex_, '| ours, PnP route, stale')
    assert '| 77.0 |' in row(complex_, '| oracle geometry (simulator calibration) |')
    assert '| 76.0 |' in row(complex_, "| static camera: first frame's calibration |")
    assert '| 75.0 |' in row(complex_, '| static camera: reference calibration |')
    for part, variant in ((simple, 'simple'), (complex_, 'complex')):
        static = row(part, '| static-trained model')
        assert f'`{variant}_static`' in static and '| 3.3 |' in static and '| 4.4 |' in static
    # Paper rows in their columns (DETAIL: MODA MODP precision recall MOTA MOTP IDF1 MT ML HOTA DetA AssA).
    assert row(simple, '| paper: EarlyBird |').endswith('|  |  | 94 |  |  | 95.9 |  |  |  |  |  |  |  |  |')
    assert row(simple, '| paper: TrackTacular |').endswith('|  |  |  |  |  |  | 92.7 |  | 79.64 |  |  |  |  |  |')
    assert 'marginally lower' in row(simple, '| paper: the proposed method')
    assert row(complex_, '| paper: TrackTacular |').endswith('|  |  | 5.72 |  |  |  | 31.44 |  |  | 0 |  |  |  |  |')
    assert row(complex_, '| paper: proposed |').endswith('|  |  | ~89 |  | ~97 | ~86 | ~88.5 |  |  | ~80 |  |  |  |  |')
    assert '| HOTA | DetA | AssA |' in simple and 'HOTA/DetA/AssA as TrackEval computes them' in text
    # 2: transfer sweep, every share, the paper's figures beside the 50 % rows, and the discussion.
    transfer = section(text, '## 2. Transfer')
    for share in size.transfer_shares:
        scratch, pretrained = (
            row(transfer, f'| {100 * share:g} % | {size.frames_of_share(share)} | from scratch |'),
            row(transfer, f'| {100 * share:g} % | {size.frames_of_share(share)} | pretrained on complex'),
        )
        assert f'| {100 * (0.30 + share / 2):.1f} |' in scratch and f'| {100 * (0.45 + share / 4):.1f} |' in pretrained
        assert ('MODA ~54, MODP >80' in scratch) == (share == 0.5) and ('MODA ~69, MODP >80' in pretrained) == (
            share == 0.5
        )
    assert '| 33.3 |' in row(transfer, '| 0 % | 0 | `complex_s0` without fine-tuning |')
    assert '| 60.0 | 55.0 | 65.0 | 46.5 |' in row(transfer, '| 0 % | 0 | `complex_s0` without fine-tuning |')
    assert '**Discussion' in transfer and '+15 MODA points at 50 %' in transfer
    # 3: mean +- std over the subsets, with the paper's dropout figures for that variant and rate.
    quarter, three_quarters = row(text, '| complex | 0.25 |'), row(text, '| complex | 0.75 |')
    assert '| 72.0 ± 2.0 |' in quarter and 'MODA >80; MOTA >80' in quarter
    assert '| 40.0 ± 10.0 |' in three_quarters and 'MODA ~36; MOTA ~40' in three_quarters
    assert '| 2 | 3 |' in row(text, '| complex | 0.75 |')  # 2 views kept, 3 subsets
    assert quarter.endswith('| 80.0 ± 0.0 | 55.0 ± 0.0 | MODA >80; MOTA >80 |')  # MOTP, then HOTA
    # 4: RANSAC seeds on the main model with their mean +- std; training seeds as a second table.
    variation, training = section(text, '## 4. Run-to-run').split('### Training-seed variation')
    n = len(size.ransac_seeds)
    moda = [60 + 2 * k for k in size.ransac_seeds]
    mean = sum(moda) / n
    std = (sum((m - mean) ** 2 for m in moda) / (n - 1)) ** 0.5
    assert f'**{mean:.1f} ± {std:.1f}**' in row(variation, f'| **mean ± std ({n} runs)** |')
    assert '| 1 | 71.2 |' in training and '**70.8 ± 9.4**' in row(training, '| **mean ± std (3 runs)** |')
    assert 'MAGSAC' in variation and 'MODA 80.0' in variation and 'deterministic' in variation
    # 5: Table III quoted with the reason, and the MultiviewX readers' agreement.
    table3 = section(text, '## 5. Stationary')
    assert 'cannot be downloaded' in table3
    assert row(table3, '| TrackTacular |') == '| TrackTacular | 91.8 | 79.8 | 89.6 | 81.7 | 95.9 | 89.2 | 91.4 | 86.7 |'
    assert row(table3, '| MVTT |') == '| MVTT | 94.1 | 81.3 | - | - | 95.0 | 92.8 | - | - |'
    assert row(table3, '| C1 |') == '| C1 | 200 | 3.1 | 9.9 | 2.50 | 10.1 |'
    # 6: the default model through the live graph on the real sample, labelled as its validation set.
    real_data = section(text, '## 6. Real data')
    assert (
        row(real_data, '| `detector_seed1.pt` (sha256 abababababab) |')
        == '| `detector_seed1.pt` (sha256 abababababab) | 10 | 99.0 | 75.0 | 90.0 | 85.0 | 92.5 '
        '| 80.0 | 60.0 | 70.0 | 10.0 | 55.0 | 65.0 | 46.5 |'
    )
    assert 'real validation set' in real_data and 'no test accuracy' in real_data and 'run_graph' in real_data
    # settings and machine.
    assert 'Test CPU 9000' in text and 'abc123' in text and f'{size.image_width}x{size.image_height}' in text
    images = tmp_path / 'docs' / 'images' / 'results'
    for name in ('exp1_simple.png', 'exp1_complex.png', 'exp2_transfer.png', 'exp3_dropout.png'):
        assert (images / name).read_bytes()[:8] == PNG
        assert f'](images/results/{name})' in text


def _git(repo, *args):
    return subprocess.run(['git', '-C', str(repo), *args], capture_output=True, text=True, check=True).stdout.strip()


def test_report_flags_steps_older_than_the_code_they_depend_on(tmp_path):
    repo = tmp_path / 'repo'
    core = repo / 'ros2_ws/src/matrix_core/matrix_core'
    for sub in ('sim', 'bev', 'register'):
        (core / sub).mkdir(parents=True)
        (core / sub / 'a.py').write_text('x = 1\n')
    _git(tmp_path, 'init', '-q', str(repo))
    for args in (('add', '-A'), ('-c', 'user.name=t', '-c', 'user.email=t@t', 'commit', '-qm', 'one')):
        _git(repo, *args)
    first = _git(repo, 'rev-parse', 'HEAD')
    (core / 'bev' / 'a.py').write_text('x = 2\n')
    for args in (('add', '-A'), ('-c', 'user.name=t', '-c', 'user.email=t@t', 'commit', '-qm', 'two')):
        _git(repo, *args)
    second = _git(repo, 'rev-parse', 'HEAD')
    for sub in ('checkpoints', 'configs'):  # a new shipped model and its config: no code the experiments run
        (core / 'bev' / sub).mkdir()
        (core / 'bev' / sub / 'detector.pt').write_text('weights\n')
    for args in (('add', '-A'), ('-c', 'user.name=t', '-c', 'user.email=t@t', 'commit', '-qm', 'three')):
        _git(repo, *args)
    done = {
        'data/simple_train': {'kind': 'simulate', 'commit': first, 'dirty': False},
        'train/simple_s0': {'kind': 'train', 'commit': first, 'dirty': False},
        'train/complex_s0': {'kind': 'train', 'commit': second, 'dirty': False},
        'geometry/complex_test_registration': {'kind': 'register', 'commit': first, 'dirty': False},
        'eval/old': {'kind': 'evaluate'},
        'data/edited': {
            'kind': 'simulate',
            'commit': first,
            'dirty': True,
            'dirty_paths': ['ros2_ws/src/matrix_core/matrix_core/sim/a.py'],
        },
        'geometry/readme_edited': {'kind': 'register', 'commit': first, 'dirty': True, 'dirty_paths': ['README.md']},
    }
    write_run(tmp_path / 'run', QUICK, variant_rows(QUICK), {}, done=done)
    text = write_report(tmp_path / 'run', tmp_path / 'RESULTS.md', repo=repo).read_text()
    prov = section(text, '## Code and provenance')
    assert f'`{_git(repo, "rev-parse", "HEAD")[:12]}`' in prov and f'`{first[:12]}`' in prov
    assert '**3 of 7 steps were made by an older commit than HEAD (or with local changes)' in prov
    assert '`data/edited`: made at' in prov and 'uncommitted local changes to sim' in prov
    assert 'readme_edited' not in prov  # local changes elsewhere do not matter
    assert '`train/simple_s0`: made at' in prov and 'bev changed since' in prov
    assert '`eval/old`: made by an unknown commit' in prov
    assert 'data/simple_train' not in prov and 'complex_test_registration' not in prov  # their code is unchanged
    assert 'train/complex_s0' not in prov  # only checkpoints and configs changed in bev/ since


def test_report_needs_a_run(tmp_path):
    with pytest.raises(FileNotFoundError, match='run.json'):
        write_report(tmp_path, tmp_path / 'RESULTS.md')


def test_report_lists_evaluations_with_failed_frames(tmp_path):
    """An evaluation step whose frames partly failed is listed with its counts."""
    records = variant_rows(QUICK)
    k = next(
        i
        for i, r in enumerate(records)
        if r['model'] == 'complex_s0'
        and r['test'] == 'complex'
        and r['calibration'] == 'ground_truth'
        and not r['dropped']
    )
    records[k] = {
        **records[k],
        'num_frames': 10,
        'failures': {'frames_failed': 2, 'frames_scored': 8, 'views_masked': 3},
    }
    write_run(tmp_path / 'run', QUICK, records, {'eval/x': {'state': 'done', 'wall_s': 1.0}}, table=TABLE)
    text = write_report(tmp_path / 'run', tmp_path / 'docs' / 'RESULTS.md', repo=tmp_path).read_text()
    assert '## Evaluations with failed frames or masked views' in text
    assert 'complex_s0 on complex (ground_truth, views' in text and '2 of 10 frames failed, 3 views masked' in text
    assert 'Did not run' in section(text, '## 6. Real data')  # no live-graph step in this run
