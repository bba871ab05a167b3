"""Test-wide fixtures: the real MATRIX sample, DDS isolation, paths of built node executables."""

import os
import random
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
SHARED = Path(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared'))
# Test-only helper modules (e.g. ros_helpers), importable from tests/ and ros2_ws/src/*/test/ alike: with
# --import-mode=importlib the test folders are no packages and nothing else puts them on the path.
sys.path.insert(0, str(ROOT / 'tests' / 'helpers'))

# Every test run gets its own DDS domain on the loopback only, so parallel runs never see each other.
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.setdefault('ROS_DOMAIN_ID', str(random.Random(os.getpid()).randint(5, 95)))


@pytest.fixture(scope='session')
def shared_dir() -> Path:
    if not SHARED.is_dir():
        pytest.fail(f'shared data folder {SHARED} is missing (set MATRIX_SHARED); tests need the real sample')
    return SHARED


@pytest.fixture(scope='session')
def matrix_sample(shared_dir) -> Path:
    path = shared_dir / 'matrix_sample'
    if not path.is_dir():
        pytest.fail(f'real MATRIX sample {path} is missing')
    return path


@pytest.fixture(scope='session')
def install_dir() -> Path:
    path = ROOT / 'ros2_ws' / 'install'
    if not path.is_dir():
        pytest.fail('ros2_ws/install is missing: run `make setup` (colcon build) first')
    return path


@pytest.fixture(scope='session')
def node_executable(install_dir):
    """node_executable(package, name) -> path of a colcon-installed node, as `ros2 run` would find it."""

    def find(package: str, name: str) -> Path:
        path = install_dir / package / 'lib' / package / name
        if not path.is_file():
            pytest.fail(f'{path} not built: run `make build`')
        return path

    return find
