"""Runs a plan step by step in a run folder, skipping steps whose results are already there.

A step writes into ``<run>/<name>/``; its params go to ``<run>/steps/<name>.started.json`` before and
``.done.json`` (with the wall time) after. A step started with other params, or unfinished, is redone
from an empty folder - except an unfinished training, which resumes from its ``last.pt``. A step that
fails is logged (``<name>.error.txt``) and the steps that need it are skipped; the run goes on, and
``run.json`` lists every step's state for the report (rewritten after each step, so a run killed midway
says how far it got). With ``jobs`` > 1, steps whose needs are finished run at once in that many worker
processes (one torch thread each, in plan order). Inside an evaluation step, a frame that fails is not scored
and a view whose image or calibration fails is masked; its ``metrics.json`` lists them (``failures``). The
network's device (``matrix_core.device``) is resolved once, before the first step, recorded in ``run.json``
(``machine``) and given to the executors that take a ``device`` (training, evaluation); a cached step is not
redone for another device.
"""

import dataclasses
import inspect
import json
import multiprocessing
import shutil
import time
import traceback
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

import torch

from matrix_core.device import DEFAULT_DEVICE, resolve_device
from matrix_core.experiments.machine import code_commit, machine_info
from matrix_core.experiments.steps import EXECUTORS, StepUnavailable

DONE, CACHED, UNAVAILABLE, FAILED, SKIPPED = 'done', 'cached', 'unavailable', 'failed', 'skipped'
RUN_FILE = 'run.json'


def _read_json(path: Path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def record_path(run_dir: Path, name: str, what: str) -> Path:
    """Bookkeeping file of a step, outside its folder (a simulator or writer wants an empty folder):
    ``<run>/steps/<name>.<what>`` with ``what`` in started.json, done.json, error.txt."""
    return run_dir / 'steps' / f'{name}.{what}'


def _prepare(step, run_dir: Path) -> bool:
    """True when the step's folder already holds its finished result; else leave it ready to run."""
    out, started, done = (
        run_dir / step.name,
        record_path(run_dir, step.name, 'started.json'),
        record_path(run_dir, step.name, 'done.json'),
    )
    previous = _read_json(started)
    if previous == step.params and done.is_file():
        return True
    done.unlink(missing_ok=True)
    record_path(run_dir, step.name, 'error.txt').unlink(missing_ok=True)
    if out.exists() and (previous != step.params or step.kind != 'train'):
        shutil.rmtree(out)
    started.parent.mkdir(parents=True, exist_ok=True)
    started.write_text(json.dumps(step.params, indent=2))
    return False


def run_step(step, run_dir: Path, progress: bool, log, device: str) -> dict:
    """Run one step (or find it cached); ``device`` (resolved, e.g. 'cpu', 'cuda:0') goes to an executor that
    takes one."""
    out = run_dir / step.name
    if _prepare(step, run_dir):
        return {'state': CACHED, 'wall_s': _read_json(record_path(run_dir, step.name, 'done.json'))['wall_s']}
    start = time.perf_counter()
    execute = EXECUTORS[step.kind]
    on_device = {'device': device} if 'device' in inspect.signature(execute).parameters else {}
    try:
        execute(step.params, out, run_dir, progress, log, **on_device)
    except StepUnavailable as exc:
        log(f'{step.name}: not run: {exc}')
        return {'state': UNAVAILABLE, 'reason': str(exc)}
    except Exception as exc:  # one broken step must not end a run of hours; it is reported loudly
        error = record_path(run_dir, step.name, 'error.txt')
        error.write_text(traceback.format_exc())
        log(f'{step.name}: FAILED: {type(exc).__name__}: {exc} (traceback in {error})')
        return {'state': FAILED, 'reason': f'{type(exc).__name__}: {exc}'.splitlines()[0][:300]}
    wall = time.perf_counter() - start
    record_path(run_dir, step.name, 'done.json').write_text(
        json.dumps(
            {
                'name': step.name,
                'kind': step.kind,
                'params': step.params,
                'wall_s': wall,
                **({'device': device} if on_device else {}),
                **code_commit(),
                'finished_utc': time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime()),
            },
            indent=2,
        )
    )
    return {'state': DONE, 'wall_s': wall}


def _blocked(step, states: dict, planned: set):
    """(name, state) of the first need that ended without a result, 'wait' when a need is still to come,
    or None when the step can run."""
    for n in step.needs:
        state = states.get(n, {}).get('state')
        if state in (DONE, CACHED):
            continue
        if state is None and n in planned:
            return n, 'wait'
        return n, state or 'not planned'
    return None


def _in_worker(step, run_dir: Path, threads: int, device: str) -> dict:
    """One step in a worker process (progress bars off: several would interleave)."""
    torch.set_num_threads(threads)
    return run_step(step, run_dir, False, print, device)


def _run_parallel(
    plan: list, run_dir: Path, threads: int, jobs: int, bar, states: dict, step_done, device: str
) -> None:
    """Run ``plan`` with ``jobs`` steps at once (spawned workers: no forked torch state), in plan order."""
    planned, pending, running = {s.name for s in plan}, list(plan), {}
    with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context('spawn')) as pool:
        while pending or running:
            for step in list(pending):
                if len(running) >= jobs:
                    break
                blocked = _blocked(step, states, planned)
                if blocked and blocked[1] == 'wait':
                    continue
                pending.remove(step)
                if blocked:
                    states[step.name] = {'state': SKIPPED, 'reason': f'needs {blocked[0]}, which was {blocked[1]}'}
                    bar.update()
                    step_done()
                    continue
                running[pool.submit(_in_worker, step, run_dir, threads, device)] = step
            if not running:
                continue
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                step = running.pop(future)
                try:
                    result = future.result()
                except Exception as exc:  # a worker that died (e.g. out of memory)
                    result = {'state': FAILED, 'reason': f'worker died: {type(exc).__name__}: {exc}'[:300]}
                states[step.name] = {'kind': step.kind, **result}
                bar.set_postfix_str(step.name)
                bar.update()
                step_done()


def run_plan(
    plan: list,
    size,
    run_dir,
    threads: int = 1,
    progress: bool = True,
    log=print,
    repo=None,
    jobs: int = 1,
    device: str = DEFAULT_DEVICE,
) -> dict:
    """Run every step of ``plan`` (in order; ``jobs`` at once) under ``run_dir``; returns and writes ``run.json``.
    ``device``: the network's (``matrix_core.device``), resolved before the first step."""
    from tqdm import tqdm

    device = str(resolve_device(device, log))
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(threads)
    started = time.time()
    states = {}
    summary = {
        'size': {
            **dataclasses.asdict(size),
            'transfer_fraction': size.transfer_fraction,
            'transfer_frames': size.transfer_frames,
        },
        'machine': {**machine_info(threads, Path(repo or Path.cwd())), 'jobs': jobs, 'device': device},
        'started_utc': time.strftime('%Y-%m-%d %H:%M:%S', time.gmtime(started)),
        'wall_s': 0.0,
        'steps': states,
    }

    def step_done() -> None:  # after every step: a run killed midway still says how far it got
        _write_run(run_dir, summary, started)

    if jobs > 1:
        with tqdm(
            total=len(plan), desc=f'experiments ({size.name}, {jobs} jobs)', unit='step', disable=not progress
        ) as bar:
            _run_parallel(plan, run_dir, threads, jobs, bar, states, step_done, device)
        summary['steps'] = {s.name: states[s.name] for s in plan}
    else:
        bar = tqdm(plan, desc=f'experiments ({size.name})', unit='step', disable=not progress)
        planned = {s.name for s in plan}
        for step in bar:
            bar.set_postfix_str(step.name)
            blocked = _blocked(step, states, planned)
            if blocked:
                states[step.name] = {
                    'state': SKIPPED,
                    'reason': f'needs {blocked[0]}, which was {"not run" if blocked[1] == "wait" else blocked[1]}',
                }
            else:
                states[step.name] = {'kind': step.kind, **run_step(step, run_dir, progress, log, device)}
            step_done()
    _write_run(run_dir, summary, started)
    return summary


def _write_run(run_dir: Path, summary: dict, started: float) -> None:
    """``run.json`` (the steps so far), replaced atomically so a kill never leaves half a file."""
    summary['wall_s'] = time.time() - started
    tmp = run_dir / (RUN_FILE + '.tmp')
    tmp.write_text(json.dumps(summary, indent=2))
    tmp.replace(run_dir / RUN_FILE)


def run_experiments(
    size,
    out_dir,
    report,
    images=None,
    threads: int = 1,
    progress: bool = True,
    log=print,
    repo=None,
    jobs: int = None,
    metrics_dir=None,
    device: str = DEFAULT_DEVICE,
) -> tuple:
    """The whole thing: plan of ``size`` run in ``out_dir/<size.name>`` (``jobs`` steps at once, default the
    size's; the network on ``device``), its small files archived to ``metrics_dir`` (default
    ``<report folder>/results/<size>``), then the report from that archive. Returns (run summary, report path)."""
    from matrix_core.experiments.archive import archive_run, default_metrics_dir
    from matrix_core.experiments.plan import build_plan
    from matrix_core.experiments.report import write_report

    run_dir = Path(out_dir) / size.name
    summary = run_plan(build_plan(size), size, run_dir, threads, progress, log, repo, jobs or size.jobs, device)
    archive = archive_run(run_dir, metrics_dir or default_metrics_dir(report, size.name))
    return summary, write_report(archive, report, images, repo=repo)
