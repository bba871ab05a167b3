"""The installed ``matrix-tracker`` command: help, info, and clear errors."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from matrix_core.cli.main import SUBCOMMANDS

EXE = Path(sys.executable).parent / 'matrix-tracker'


def run(*args):
    return subprocess.run([str(EXE), *map(str, args)], capture_output=True, text=True, timeout=300)


def test_installed_in_venv():
    assert EXE.is_file(), 'make setup installs matrix-tracker into the venv'


@pytest.mark.parametrize('command', SUBCOMMANDS)
def test_every_subcommand_has_help(command):
    result = run(command, '--help')
    assert result.returncode == 0 and 'usage: matrix-tracker ' + command in result.stdout


def test_info_on_real_sample(matrix_sample):
    result = run('info', matrix_sample, '--json')
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)
    assert info['format'] == 'matrix' and info['views'] == [f'D{i}' for i in range(1, 9)]
    assert info['frames'] == 5 and info['people'] == 40 and info['visible_boxes'] == 1280
    lo, hi = map(float, info['camera_height_m'].split(' .. '))
    assert 11.0 < lo < hi < 13.5
    text = run('info', matrix_sample)
    assert text.returncode == 0 and 'camera_tilt_below_horizon_deg' in text.stdout


def test_errors_are_clear(tmp_path):
    missing = run('info', tmp_path / 'nope')
    assert missing.returncode == 2 and 'dataset folder not found' in missing.stderr
    empty = run('info', tmp_path)
    assert empty.returncode == 2 and 'not a MATRIX, Wildtrack or MultiviewX folder' in empty.stderr
    assert 'Traceback' not in empty.stderr
    bad = run('no-such-command')
    assert bad.returncode == 2 and 'invalid choice' in bad.stderr


def test_a_mistyped_flag_names_the_closest_one(tmp_path):
    """An unknown flag of a subcommand is an error that suggests the flag meant."""
    typo = run('simulate', '--frams', '3', '--out', tmp_path / 'sim')
    assert typo.returncode == 2 and 'unrecognized arguments: --frams 3' in typo.stderr
    assert '--frams: did you mean --frames?' in typo.stderr and not (tmp_path / 'sim').exists()
