"""The machine and code a run used (for the settings table of RESULTS.md)."""

import platform
import subprocess
from pathlib import Path

from matrix_core.locations import code_checkout


def cpu_model() -> str:
    try:
        for line in Path('/proc/cpuinfo').read_text().splitlines():
            if line.startswith('model name'):
                return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or 'unknown'


def git_commit(repo: Path) -> str:
    """``<hash>`` plus ``+local changes`` when the working tree differs from it (read-only git calls)."""
    try:
        head = subprocess.run(
            ['git', '-C', str(repo), 'rev-parse', '--short=12', 'HEAD'], capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ['git', '-C', str(repo), 'status', '--porcelain', '--untracked-files=no'],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        return head + (' + local changes' if dirty else '')
    except (OSError, subprocess.CalledProcessError):
        return 'unknown'


def code_commit(repo: Path = None) -> dict:
    """``{'commit': full HEAD hash or None, 'dirty': bool, 'dirty_paths': [changed tracked files]}`` of the
    repository holding this code (or ``repo``): recorded with every finished step, so a report can tell
    which steps predate the code, or ran with local changes to the code they depend on."""
    repo = Path(repo) if repo else code_checkout()
    if repo is None:
        return {'commit': None, 'dirty': False, 'dirty_paths': []}
    try:
        head = subprocess.run(
            ['git', '-C', str(repo), 'rev-parse', 'HEAD'], capture_output=True, text=True, check=True
        ).stdout.strip()
        status = subprocess.run(
            ['git', '-C', str(repo), 'status', '--porcelain', '--untracked-files=no'],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.splitlines()
        paths = [line[3:].split(' -> ')[-1] for line in status if line.strip()]
        return {'commit': head, 'dirty': bool(paths), 'dirty_paths': paths[:200]}
    except (OSError, subprocess.CalledProcessError):
        return {'commit': None, 'dirty': False, 'dirty_paths': []}


def machine_info(threads: int, repo: Path) -> dict:
    import os

    import torch

    return {
        'cpu': cpu_model(),
        'cpu_count': os.cpu_count(),
        'threads': threads,
        'torch': torch.__version__,
        'python': platform.python_version(),
        'platform': platform.platform(),
        'git_commit': git_commit(repo),
    }
