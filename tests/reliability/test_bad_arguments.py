"""A bad argument of every ``matrix-tracker`` subcommand, and of every kind of launch argument (through
``run_graph``, which takes the launch's settings under the same names): exit code 2, one line naming the
argument, no traceback, nothing written, before any work."""

import subprocess
import sys
from pathlib import Path

import pytest

from matrix_core.cli.main import SUBCOMMANDS

EXE = Path(sys.executable).parent / 'matrix-tracker'

# one bad argument per subcommand: what the error must name
BAD = {
    'info': (['{tmp}/nowhere'], 'dataset folder not found'),
    'bag': (['{sample}'], '--out BAG is required'),
    'track': (['{tmp}/missing.txt', '--out', '{tmp}/out/tracks.txt'], 'missing.txt'),
    'score': (['{tmp}/gt.txt', '{tmp}/pred.txt', '--threshold', '-1'], 'argument --threshold'),
    'register': (['{sample}', '--out', '{tmp}/out', '--max-frames', '-1'], 'argument --max-frames: -1 is negative'),
    'train': (['--config', 'sample', '--out', '{tmp}/out', '--epochs', '0'], 'argument --epochs'),
    'evaluate': (
        ['{sample}', '--checkpoint', 'detector_seed1.pt', '--out', '{tmp}/out', '--frames', '-1', '3'],
        'argument --frames: -1 is negative',
    ),
    'calibrate': (['{sample}', '--out', '{tmp}/out', '--frame-period', '0'], 'argument --frame-period'),
    'simulate': (['--frames', '-1', '--out', '{tmp}/out'], 'frames must be >= 1'),
    'evaluate-recording': (['{tmp}/rec', '--ground-truth', '{tmp}/bag', '--iou', '2'], 'argument --iou'),
    'experiments': (['--out', '{tmp}/out', '--jobs', '0'], 'argument --jobs'),
    'site': (['check', '{tmp}/nowhere.yaml'], 'nowhere.yaml'),
}


def test_every_subcommand_has_a_bad_argument_case():
    assert sorted(BAD) == sorted(SUBCOMMANDS)


@pytest.mark.parametrize('command', SUBCOMMANDS)
def test_a_bad_argument_is_one_clear_line(command, matrix_sample, tmp_path):
    args, named = BAD[command]
    words = [a.format(tmp=tmp_path, sample=matrix_sample) for a in args]
    run = subprocess.run([str(EXE), command, *words], capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, run.stdout + run.stderr
    assert named in run.stderr and 'error' in run.stderr and 'Traceback' not in run.stderr, run.stderr
    assert not (tmp_path / 'out').exists()


# one per kind of launch argument (GraphSettings field types), as run_graph and `ros2 launch` take them
LAUNCH_BAD = {
    'str (a path)': (['--bag', '{tmp}/nowhere'], 'not a rosbag2 folder'),
    'str (the dataset)': (['--dataset', '{tmp}/nowhere'], 'dataset folder not found'),
    'int': (['--drones_per_process', '-1'], 'drones_per_process must be >= 0'),
    'float': (['--rate', '0'], 'rate must be positive'),
    'float (not a number)': (['--rate', 'fast'], "argument --rate: invalid float value: 'fast'"),
    'bool': (['--lockstep', 'maybe'], "argument --lockstep: expected true/false, got 'maybe'"),
    'list': (['--views'], 'views must name at least one drone'),
    'unknown': (['--lockstep_timeot', '3'], 'unrecognized arguments'),
}


@pytest.mark.parametrize('kind', sorted(LAUNCH_BAD))
def test_a_bad_launch_argument_stops_before_anything_starts(kind, matrix_sample, node_executable, tmp_path):
    args, named = LAUNCH_BAD[kind]
    base = {'--bag': str(tmp_path / 'nowhere_bag'), '--dataset': str(matrix_sample)}
    words = [a.format(tmp=tmp_path) for a in args]
    for flag, value in base.items():
        if flag not in words:
            words = [flag, value, *words]
    logs = tmp_path / 'logs'
    run = subprocess.run(
        [str(node_executable('matrix_bringup', 'run_graph')), *words, '--log_dir', str(logs)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2, run.stdout + run.stderr
    assert named in run.stderr and 'Traceback' not in run.stderr, run.stderr
    assert not logs.exists()  # no process was started
