"""Which code made each step of a run, and whether that code has changed since (for RESULTS.md).

Every finished step records the commit it ran at (``done.json``: ``commit``, ``dirty``). A step is
*stale* when the last commit that touched the code it depends on (``git log -1 -- <paths>``) is not an
ancestor of (or equal to) the step's commit: its numbers may no longer describe the code at HEAD. A
step that ran with uncommitted changes to that code (``dirty_paths``) is flagged too.
"""

import subprocess
from pathlib import Path

CORE = 'ros2_ws/src/matrix_core/matrix_core/'
# The experiments train and evaluate their own models: the shipped checkpoints and training configs in bev/ are
# not code they run (git pathspecs; a new default checkpoint reruns the live-graph step through its cache key).
BEV_CODE = (CORE + 'bev', f':(exclude){CORE}bev/checkpoints', f':(exclude){CORE}bev/configs')
# Step kind -> code it depends on (git pathspecs relative to the repository root).
CODE_PATHS = {
    'simulate': (CORE + 'sim',),
    'calibrate': (CORE + 'calib',),
    'register': (CORE + 'register',),
    'train': BEV_CODE,
    # an evaluation tracks its detections and scores them: tracker or metric changes change its numbers
    'evaluate': (*BEV_CODE, CORE + 'tracking', CORE + 'metrics'),
    'readers': (CORE + 'datasets',),
    'live_graph': (
        CORE + 'calib',
        CORE + 'register',
        CORE + 'bev',
        CORE + 'fusion',
        CORE + 'tracking',
        CORE + 'metrics',
        *(
            f'ros2_ws/src/{pkg}'
            for pkg in ('matrix_calib', 'matrix_register', 'matrix_bev_tracker', 'matrix_ros', 'matrix_bringup')
        ),
    ),
}


def _git(repo: Path, *args) -> subprocess.CompletedProcess:
    return subprocess.run(['git', '-C', str(repo), *args], capture_output=True, text=True)


def head_commit(repo) -> str:
    r = _git(Path(repo), 'rev-parse', 'HEAD')
    return r.stdout.strip() if r.returncode == 0 else None


def last_change(repo, paths) -> str:
    """Full hash of the last commit touching ``paths`` (None outside git or for untracked paths)."""
    r = _git(Path(repo), 'log', '-1', '--format=%H', '--', *paths)
    return (r.stdout.strip() or None) if r.returncode == 0 else None


def is_ancestor(repo, older: str, newer: str) -> bool:
    """True when ``older`` is ``newer`` or one of its ancestors (None when git cannot tell)."""
    r = _git(Path(repo), 'merge-base', '--is-ancestor', older, newer)
    return {0: True, 1: False}.get(r.returncode)


def _touches(dirty_paths, paths) -> bool:
    """Whether local changes (None: not recorded, assume yes) touch any of ``paths``."""
    if dirty_paths is None:
        return True
    return any(d == p or d.startswith(p.rstrip('/') + '/') for d in dirty_paths for p in paths)


def stale_steps(repo, done: dict) -> dict:
    """``{step name: reason}`` for the steps of ``done`` (name -> done.json record) whose code changed
    after the commit they ran at, or whose commit is unknown or had local changes."""
    out, cache = {}, {}
    for name, record in sorted(done.items()):
        paths = CODE_PATHS.get(record.get('kind'))
        if not paths:
            continue
        commit = record.get('commit')
        if not commit:
            out[name] = 'made by an unknown commit (a run before commits were recorded)'
            continue
        if paths not in cache:
            cache[paths] = last_change(repo, paths)
        last = cache[paths]
        if last is None:
            continue
        ancestor = is_ancestor(repo, last, commit)
        where = ', '.join(p.replace(CORE, '') for p in paths if not p.startswith(':('))
        if ancestor is None:
            out[name] = (
                f'made at {commit[:12]}, not in this repository\'s history ({where} last changed at {last[:12]})'
            )
        elif not ancestor:
            out[name] = f'made at {commit[:12]}; {where} changed since (last at {last[:12]})'
        elif record.get('dirty') and _touches(record.get('dirty_paths'), paths):
            out[name] = f'made at {commit[:12]} with uncommitted local changes to {where}'
    return out
