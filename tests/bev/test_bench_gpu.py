"""scripts/bench_gpu.py runs on the CPU as a smoke run (``--device cpu --quick``) and prints its one table: every
stage for each view count, the training step and the CPU-device equality check, which must pass."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STAGES = ('prepare (CPU, 1 thread)', 'copy to device', 'lifting', 'network', 'decoding', 'fuse network total')


def test_bench_gpu_quick_on_the_cpu_prints_the_table():
    run = subprocess.run(
        [sys.executable, str(ROOT / 'scripts' / 'bench_gpu.py'), '--device', 'cpu', '--quick', '--iterations', '1'],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    lines = run.stdout.splitlines()
    assert lines[0].startswith('device: CPU') and '(cpu)' in lines[0]
    rows = [[cell.strip() for cell in line.strip('|').split('|')] for line in lines if line.startswith('| ')]
    assert rows[0] == ['stage', 'views', 'ms per frame', 'per second', 'note']
    found = {(r[0], r[1]) for r in rows[1:]}
    assert {(stage, views) for stage in STAGES for views in ('2', '4')} <= found
    totals = [r for r in rows if r[0] == 'fuse network total']
    assert all(float(r[2]) > 0 and float(r[3]) > 0 for r in totals)
    (train,) = [r for r in rows if r[0] == 'training step']
    assert train[1] == '2' and float(train[3]) > 0
    (check,) = [r for r in rows if r[0] == 'CPU-device equality']
    assert check[4].startswith('ok:'), check
