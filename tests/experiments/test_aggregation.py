"""Small pieces of the experiments on tiny inputs: mean/std over runs, picking the RANSAC-seed records,
the transfer discussion, the archive of a run, and the MultiviewX readers step on the real sample."""

import json
import math

import pytest

from matrix_core.experiments.archive import archive_run, default_metrics_dir
from matrix_core.experiments.records import mean_std, one, select
from matrix_core.experiments.transfer_text import transfer_discussion


def test_mean_and_sample_std_over_runs():
    assert mean_std([1.0, 2.0, 3.0]) == (2.0, 1.0)  # std with n - 1
    mean, std = mean_std([10.0, 12.0, math.nan, 14.0, 16.0])  # nan = a run without a number
    assert mean == 13.0 and std == pytest.approx(math.sqrt(20 / 3))
    mean, std = mean_std([5.0])
    assert mean == 5.0 and math.isnan(std)
    assert all(math.isnan(x) for x in mean_std([math.nan]))


def test_ransac_seed_records_are_kept_apart_from_the_live_one():
    live = {'model': 'm', 'test': 'complex', 'calibration': 'registration', 'dropped': [], 'ransac_seed': None}
    old = {'model': 'm', 'test': 'complex', 'calibration': 'registration', 'dropped': []}  # before the field
    seeded = [{**live, 'ransac_seed': k} for k in range(3)]
    assert one([*seeded, live], model='m', calibration='registration') is live
    assert one([*seeded, old], model='m', calibration='registration') is old
    assert one([*seeded, live], model='m', calibration='registration', ransac_seed=2) is seeded[2]
    assert len(select([*seeded, live], calibration='registration')) == 4


def test_transfer_discussion_follows_the_numbers():
    helps_small = transfer_discussion({0.05: (20.0, 40.0), 0.5: (60.0, 60.5)}, 0.5, 54, 69)
    assert '+15 MODA points at 50 %' in helps_small and '+20.0 at 5 %, +0.5 at 50 %' in helps_small
    assert 'only with less data (5 %)' in helps_small
    at_paper = transfer_discussion({0.25: (30.0, 31.0), 0.5: (50.0, 60.0)}, 0.5, 54, 69)
    assert "appears at its share, comparable in size (+10.0 against +15)" in at_paper
    small = transfer_discussion({0.5: (50.0, 53.0)}, 0.5, 54, 69)
    assert 'but much smaller (+3.0 against +15)' in small
    never = transfer_discussion({0.05: (40.0, 39.0), 0.5: (60.0, 55.0)}, 0.5, 54, 69)
    assert 'does not appear at any measured share' in never and 'worse at 50 %' in never
    assert 'No share was measured' in transfer_discussion({0.5: (math.nan, 50.0)}, 0.5, 54, 69)
    # The complex model as it is, against the fine-tuned ones: said only when it beats all of them.
    as_is = transfer_discussion({0.05: (40.0, 80.0), 0.5: (60.0, 55.0)}, 0.5, 54, 69, without_fine_tuning=85.5)
    assert 'without any fine-tuning (MODA 85.5) beats every fine-tuned one (best 80.0)' in as_is
    assert 'without any fine-tuning' not in transfer_discussion(
        {0.05: (40.0, 80.0)}, 0.5, 54, 69, without_fine_tuning=81.0
    )
    assert 'without any fine-tuning' not in transfer_discussion({0.05: (40.0, 80.0)}, 0.5, 54, 69)


def test_archive_keeps_the_small_per_step_files(tmp_path):
    run = tmp_path / 'run'
    for rel, text in {
        'run.json': '{}',
        'steps/eval/a.done.json': '{"commit": "x"}',
        'eval/a/metrics.json': '{}',
        'eval/a/trajectories.png': 'png',
        'tables/multiviewx_sample/metrics.json': '{}',
        'train/m/last.pt': 'big',
        'data/x/img.jpg': 'big',
        'steps/eval/a.started.json': '{}',
    }.items():
        (run / rel).parent.mkdir(parents=True, exist_ok=True)
        (run / rel).write_text(text)
    dest = archive_run(run, default_metrics_dir(tmp_path / 'docs' / 'RESULTS.md', 'quick'))
    assert dest == tmp_path / 'docs' / 'results' / 'quick'
    kept = sorted(str(p.relative_to(dest)) for p in dest.rglob('*') if p.is_file())
    assert kept == [
        'eval/a/metrics.json',
        'eval/a/trajectories.png',
        'run.json',
        'steps/eval/a.done.json',
        'tables/multiviewx_sample/metrics.json',
    ]
    (run / 'eval/a/metrics.json').unlink()
    archive_run(run, dest)  # a new archive replaces the old one
    assert not (dest / 'eval/a/metrics.json').exists()
    with pytest.raises(FileNotFoundError, match='run.json'):
        archive_run(tmp_path / 'nothing', dest)


def test_readers_step_on_the_real_multiviewx_sample(tmp_path, shared_dir, monkeypatch):
    from matrix_core.experiments.steps import EXECUTORS, StepUnavailable

    monkeypatch.setenv('MATRIX_SHARED', str(shared_dir))
    EXECUTORS['readers']({'dataset': 'shared:multiviewx_sample'}, tmp_path / 'out', tmp_path, False, print)
    result = json.loads((tmp_path / 'out' / 'metrics.json').read_text())
    assert result['format'] == 'MultiviewXDataset' and result['frames'] == 10
    assert list(result['views']) == ['C1', 'C2', 'C3', 'C4', 'C5', 'C6']
    for view, v in result['views'].items():  # the sample's README: median 3.1-7.0 px per camera
        assert v['n'] > 150 and v['median_px'] <= 8.0 and v['p90_px'] < 25.0, view
        assert v['camera_height_m'] == pytest.approx(2.5, abs=0.01)
    monkeypatch.setenv('MATRIX_SHARED', str(tmp_path / 'missing'))
    with pytest.raises(StepUnavailable, match='MATRIX_SHARED'):
        EXECUTORS['readers']({'dataset': 'shared:multiviewx_sample'}, tmp_path / 'out2', tmp_path, False, print)


def test_live_graph_step_needs_the_real_sample(tmp_path, monkeypatch):
    from matrix_core.experiments import real_live
    from matrix_core.experiments.steps import EXECUTORS, StepUnavailable

    monkeypatch.setenv('MATRIX_SHARED', str(tmp_path / 'missing'))
    with pytest.raises(StepUnavailable, match='MATRIX_SHARED'):
        EXECUTORS['live_graph'](real_live.step_params('detector_seed1.pt'), tmp_path / 'out', tmp_path, False, print)
    assert (
        real_live.step_params('detector_seed0.pt')['checkpoint_sha256']
        != real_live.step_params('detector_seed1.pt')['checkpoint_sha256']
    )  # another model is another cache key


def test_two_jobs_run_ready_steps_and_skip_those_after_a_missing_one(tmp_path, shared_dir, monkeypatch):
    from matrix_core.experiments.plan import Step
    from matrix_core.experiments.runner import run_plan
    from matrix_core.experiments.sizes import QUICK

    monkeypatch.setenv('MATRIX_SHARED', str(shared_dir))  # spawned workers inherit the environment
    sample, missing = {'dataset': 'shared:multiviewx_sample'}, {'dataset': 'shared:no_such_folder'}
    plan = [
        Step('tables/a', 'readers', sample),
        Step('tables/b', 'readers', missing),
        Step('tables/c', 'readers', sample, ('tables/b',)),
        Step('tables/d', 'readers', sample, ('tables/a',)),
    ]
    summary = run_plan(plan, QUICK, tmp_path / 'run', progress=False, repo=tmp_path, jobs=2)
    states = {name: s['state'] for name, s in summary['steps'].items()}
    assert list(states) == ['tables/a', 'tables/b', 'tables/c', 'tables/d']  # plan order kept
    assert states == {'tables/a': 'done', 'tables/b': 'unavailable', 'tables/c': 'skipped', 'tables/d': 'done'}
    assert 'needs tables/b, which was unavailable' in summary['steps']['tables/c']['reason']
    done = json.loads((tmp_path / 'run' / 'steps' / 'tables' / 'a.done.json').read_text())
    assert len(done['commit']) == 40 and done['kind'] == 'readers'  # the code's commit
    again = run_plan(plan, QUICK, tmp_path / 'run', progress=False, repo=tmp_path, jobs=2)
    assert again['steps']['tables/a']['state'] == again['steps']['tables/d']['state'] == 'cached'
