"""The quick mode end to end on an even smaller size: every step runs (real simulator, calibration,
registration, training, evaluation), RESULTS.md and its PNGs come from the run's metrics.json files,
and a rerun finds everything cached."""

import dataclasses
import json
import time

import pytest
import torch

from matrix_core.experiments.plan import build_plan
from matrix_core.experiments.records import load_records, one, value
from matrix_core.experiments.runner import run_experiments
from matrix_core.experiments.sizes import QUICK
from matrix_core.experiments.steps import initialise_from

TINY = dataclasses.replace(
    QUICK,
    name='tiny',
    train_frames=4,
    test_frames=3,
    epochs=1,
    image_width=96,
    image_height=56,
    dropout_seeds=(0, 1),
    notes='test size',
)


@pytest.mark.slow
def test_quick_mode_end_to_end(tmp_path):
    out, report = tmp_path / 'out', tmp_path / 'docs' / 'RESULTS.md'
    summary, path = run_experiments(TINY, out, report, progress=False, repo=tmp_path)
    states = {name: s['state'] for name, s in summary['steps'].items()}
    assert set(states) == {s.name for s in build_plan(TINY)}
    assert set(states.values()) <= {'done', 'unavailable'}, {
        k: v for k, v in summary['steps'].items() if v['state'] not in ('done', 'unavailable')
    }
    assert sum(v == "done" for v in states.values()) >= len(states) - 3  # at most the pnp/registration evaluations
    records = load_records(out / 'tiny')
    assert len(records) == sum(1 for k, v in states.items() if k.startswith('eval/') and v == 'done')
    text = path.read_text()
    assert 'SMOKE-TEST NUMBERS' in text
    moda = value(one(records, model='complex_s0', test='complex', calibration='ground_truth'), 'MODA')
    oracle = [
        line
        for line in text.split('### Complex variant')[1].splitlines()
        if line.startswith('| oracle geometry (simulator calibration) |')
    ][0]
    assert f'| {moda:.1f} |' in oracle
    # 6: the shipped default model through the live graph on the real sample (its validation frames 0-4).
    assert states['tables/matrix_sample_live'] == 'done'
    live = json.loads((out / 'tiny' / 'tables' / 'matrix_sample_live' / 'metrics.json').read_text())
    assert live['detection']['moda'] >= 0.90 and not (out / 'tiny' / 'tables' / 'matrix_sample_live' / 'bag').exists()
    assert f'| {100 * live["detection"]["moda"]:.1f} |' in text.split('## 6. Real data')[1].split('\n## ')[0]
    images = report.parent / 'images' / 'results'
    for name in (
        'exp1_simple.png',
        'exp1_complex.png',
        'exp2_transfer.png',
        'exp3_dropout.png',
        'exp1_trajectories_complex_ground_truth.png',
    ):
        assert (images / name).stat().st_size > 1000, name
    # The report reads the archived per-step files: --report-only rewrites the same tables from them alone.
    archive = report.parent / 'results' / 'tiny'
    assert (archive / 'run.json').is_file() and len(list(archive.glob('eval/*/metrics.json'))) == len(records)
    assert all('commit' in json.loads(p.read_text()) for p in archive.glob('steps/**/*.done.json'))
    from matrix_core.experiments.report import write_report

    again_text = write_report(archive, tmp_path / 'again' / 'RESULTS.md', repo=tmp_path).read_text()
    assert oracle in again_text
    assert json.loads((out / 'tiny' / 'run.json').read_text())['size']['name'] == 'tiny'
    # A rerun resumes: every finished step is cached.
    start = time.perf_counter()
    again, _ = run_experiments(TINY, out, report, progress=False, repo=tmp_path)
    assert {n: s['state'] for n, s in again['steps'].items() if states[n] == 'done'} == {
        n: 'cached' for n, v in states.items() if v == 'done'
    }
    assert time.perf_counter() - start < 30
    # Transfer initialisation: the trainer resumes from the other model's weights at epoch 0.
    from matrix_core.bev.config import SequenceSpec, TrainConfig
    from matrix_core.bev.settings import BevSettings

    source = out / 'tiny' / 'train' / 'complex_s0' / 'last.pt'
    bev = BevSettings(model=TINY.model, image_width=TINY.image_width, image_height=TINY.image_height)
    initialise_from(source, TrainConfig(train=[SequenceSpec('unused')], bev=bev), tmp_path / 'init')
    start = torch.load(tmp_path / 'init' / 'last.pt', weights_only=False)
    trained = torch.load(source, weights_only=False)
    assert start['epoch'] == 0 and start['history'] == []
    assert all(torch.equal(trained['model'][k], v) for k, v in start['model'].items())
    with pytest.raises(ValueError, match='bev_tiny'):
        initialise_from(
            source,
            TrainConfig(train=[SequenceSpec('unused')], bev=BevSettings(model='bev_small')),
            tmp_path / 'init_small',
        )
