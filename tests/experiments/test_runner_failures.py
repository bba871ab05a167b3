"""``matrix-tracker experiments``: a failing step is recorded with its reason and traceback, the steps that
need it are skipped, the others run; ``run.json`` is rewritten after every step (a run killed midway says
how far it got); a rerun retries the failed step and finds the others cached."""

import json

from matrix_core.experiments import runner, steps
from matrix_core.experiments.plan import Step
from matrix_core.experiments.sizes import QUICK


def test_a_failing_step_is_recorded_and_the_others_run(tmp_path, monkeypatch):
    ran, seen_run_json = [], {}

    def fake(params, out, run_dir, progress, log):
        ran.append(out.name)
        if params.get('fail'):
            raise RuntimeError('injected step failure')
        if out.name == 'd':  # what run.json says while a later step runs
            seen_run_json.update(json.loads((run_dir / runner.RUN_FILE).read_text())['steps'])
        out.mkdir(parents=True, exist_ok=True)
        (out / 'result.txt').write_text(out.name)

    monkeypatch.setitem(steps.EXECUTORS, 'fake', fake)
    plan = [
        Step('a', 'fake', {}),
        Step('b', 'fake', {'fail': True}),
        Step('c', 'fake', {}, needs=('b',)),
        Step('d', 'fake', {}, needs=('a',)),
    ]
    logged = []
    summary = runner.run_plan(plan, QUICK, tmp_path, progress=False, log=logged.append, repo=tmp_path)
    states = {k: v['state'] for k, v in summary['steps'].items()}
    assert states == {'a': 'done', 'b': 'failed', 'c': 'skipped', 'd': 'done'}
    assert ran == ['a', 'b', 'd']
    assert summary['steps']['b']['reason'] == 'RuntimeError: injected step failure'
    assert summary['steps']['c']['reason'] == 'needs b, which was failed'
    assert 'injected step failure' in runner.record_path(tmp_path, 'b', 'error.txt').read_text()  # the traceback
    assert any(m.startswith('b: FAILED: RuntimeError: injected step failure') for m in logged), logged
    assert {k: v['state'] for k, v in seen_run_json.items()} == {'a': 'done', 'b': 'failed', 'c': 'skipped'}
    assert json.loads((tmp_path / runner.RUN_FILE).read_text())['steps'] == summary['steps']
    assert (tmp_path / 'a' / 'result.txt').read_text() == 'a'
    # the rerun: finished steps cached, the failed one retried (fixed now), its dependant runs
    monkeypatch.setitem(plan[1].params, 'fail', False)
    ran.clear()
    again = runner.run_plan(plan, QUICK, tmp_path, progress=False, log=logged.append, repo=tmp_path)
    assert {k: v['state'] for k, v in again['steps'].items()} == {
        'a': 'cached',
        'b': 'done',
        'c': 'done',
        'd': 'cached',
    }
    assert ran == ['b', 'c'] and not runner.record_path(tmp_path, 'b', 'error.txt').exists()
