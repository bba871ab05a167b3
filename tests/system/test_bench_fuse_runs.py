"""``scripts/bench_fuse.py`` still runs against the current fuse node (two frames per phase): its feeder must
offer what the drones offer, or the node never subscribes and the benchmark stops (it did once, when fuse
began to subscribe its geometry transient local). The figures themselves are the benchmark's, not checked."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_bench_fuse_runs_two_frames_per_phase():
    run = subprocess.run(
        [sys.executable, str(ROOT / 'scripts/bench_fuse.py'), '--frames', '2', '--cpu', '-1'],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    assert 'throughput (lockstep)' in run.stdout and 'frames lost at 2.0 Hz' in run.stdout, run.stdout[-2000:]
    assert 'fuse node per frame (median s): decode' in run.stdout
