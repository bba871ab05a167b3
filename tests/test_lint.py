"""Lint as tests: ruff (ruff.toml) and the commit-subject rule run with every `make test` and `make test-fast`.

ruff is the one pinned in constraints.txt, run from this interpreter's environment (``python -m ruff``), so
every machine checks with the same rules and the same version.
"""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# What `git log` shows in one line and what most tools cut at (the common git convention).
MAX_SUBJECT = 72


def _ruff(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, '-m', 'ruff', *args], cwd=ROOT, capture_output=True, text=True, timeout=300, check=False
    )


@pytest.fixture(scope='module')
def ruff_installed():
    version = _ruff('--version')
    if version.returncode != 0:
        pytest.fail(f'ruff is not installed in {sys.prefix} (`make setup` installs it): {version.stderr.strip()}')


def test_ruff_check_passes(ruff_installed):
    result = _ruff('check', '--no-cache', '--output-format', 'concise', '.')
    if result.returncode != 0:
        pytest.fail(f'`ruff check .` found:\n{result.stdout}{result.stderr}', pytrace=False)


def test_ruff_format_leaves_every_file_as_it_is(ruff_installed):
    result = _ruff('format', '--no-cache', '--check', '.')
    if result.returncode != 0:
        pytest.fail(
            f'`ruff format --check .` would reformat these (run `python -m ruff format FILE`):\n'
            f'{result.stdout}{result.stderr}',
            pytrace=False,
        )


def _git(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(['git', *args], cwd=ROOT, capture_output=True, text=True, timeout=60, check=False)


def long_subjects(subjects: list[str], limit: int = MAX_SUBJECT) -> list[str]:
    """The subjects longer than ``limit`` characters, each with its length."""
    return [f'{len(s)}: {s}' for s in subjects if len(s) > limit]


def test_long_subjects_are_named_with_their_length():
    assert long_subjects(['short', 'x' * 72, 'y' * 73]) == [f'73: {"y" * 73}']


def test_commit_subjects_are_at_most_72_characters():
    """Every commit since the rules came in (the first commit with ruff.toml) has a subject git shows whole."""
    if shutil.which('git') is None or _git('rev-parse', '--is-inside-work-tree').stdout.strip() != 'true':
        pytest.skip('not a git checkout')
    added = _git('log', '--diff-filter=A', '--format=%H', '--', 'ruff.toml').stdout.split()
    if not added:
        pytest.skip('no commit adds ruff.toml in this checkout')
    first = added[-1]
    # The first commit itself too: `first^..HEAD` would fail when it is the root of a shallow clone.
    subjects = [_git('log', '-1', '--format=%s', first).stdout.strip()]
    subjects += _git('log', '--format=%s', f'{first}..HEAD').stdout.splitlines()
    assert not long_subjects(subjects), (
        f'commit subjects over {MAX_SUBJECT} characters (put details in the body):\n'
        + '\n'.join(long_subjects(subjects))
    )
