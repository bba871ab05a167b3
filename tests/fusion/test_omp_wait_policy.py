"""Importing the fuse package makes idle OpenMP threads sleep unless the user chose otherwise: with
``threads: 2`` (config/fuse.yaml) spinning threads would take CPU from the drones sharing the cores."""

import os
import subprocess
import sys


def _policy_after_import(environment):
    code = 'import os, matrix_bev_tracker; print(os.environ.get("OMP_WAIT_POLICY"))'
    run = subprocess.run([sys.executable, '-c', code], env=environment, capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    return run.stdout.strip()


def test_idle_threads_sleep_by_default():
    environment = {k: v for k, v in os.environ.items() if k != 'OMP_WAIT_POLICY'}
    assert _policy_after_import(environment) == 'PASSIVE'


def test_an_explicit_policy_wins():
    assert _policy_after_import(dict(os.environ, OMP_WAIT_POLICY='ACTIVE')) == 'ACTIVE'
