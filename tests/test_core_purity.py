"""The core package must never import rclpy or ROS message/interface packages (algorithms apart from ROS), and
no core module outside ``matrix_core.cli`` imports the CLI (the CLI calls the algorithms, never the reverse)."""

import ast
import subprocess
import sys
from pathlib import Path

CORE = Path(__file__).resolve().parents[1] / 'ros2_ws' / 'src' / 'matrix_core' / 'matrix_core'
FORBIDDEN_PREFIXES = ('rclpy', 'rosidl', 'matrix_ros', 'matrix_msgs', 'builtin_interfaces', 'launch')


def _forbidden(module: str) -> bool:
    top = module.split('.')[0]
    return top.startswith(FORBIDDEN_PREFIXES) or top.endswith('_msgs') or top.endswith('_interfaces')


def imported_modules(path: Path) -> set:
    """Every module a Python file imports, at any depth (function-level imports included)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def imports_cli(path: Path) -> bool:
    """Whether a Python file imports ``matrix_core.cli`` (or a module in it) at any depth."""
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == 'matrix_core' and node.level == 0:
            if any(a.name == 'cli' for a in node.names):
                return True
    return any(m == 'matrix_core.cli' or m.startswith('matrix_core.cli.') for m in imported_modules(path))


def test_forbidden_detector_catches_ros_imports(tmp_path):
    bad = tmp_path / 'bad.py'
    bad.write_text('def f():\n    import rclpy\n    from sensor_msgs.msg import Image\n')
    assert {m for m in imported_modules(bad) if _forbidden(m)} == {'rclpy', 'sensor_msgs.msg'}


def test_no_core_source_imports_ros():
    offenders = {}
    files = sorted(CORE.rglob('*.py'))
    assert len(files) > 10
    for path in files:
        bad = sorted(m for m in imported_modules(path) if _forbidden(m))
        if bad:
            offenders[str(path.relative_to(CORE))] = bad
    assert not offenders, f'core modules import ROS packages: {offenders}'


def test_core_modules_import_with_ros_blocked():
    """Import every core module in a fresh interpreter where importing rclpy or *_msgs raises."""
    script = f'''
import importlib, pkgutil, sys
class Block:
    def find_spec(self, name, path=None, target=None):
        top = name.split('.')[0]
        if top.startswith({FORBIDDEN_PREFIXES!r}) or top.endswith('_msgs'):
            raise ImportError('core imported ' + name)
sys.meta_path.insert(0, Block())
import matrix_core
count = 0
for info in pkgutil.walk_packages(matrix_core.__path__, 'matrix_core.'):
    importlib.import_module(info.name)
    count += 1
print(count)
'''
    result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert int(result.stdout.strip()) > 10


def test_cli_detector_catches_cli_imports(tmp_path):
    for i, source in enumerate(
        (
            'def f():\n    from matrix_core.cli.main import main\n',
            'import matrix_core.cli.calibrate\n',
            'from matrix_core import cli, geometry\n',
        )
    ):
        path = tmp_path / f'bad{i}.py'
        path.write_text(source)
        assert imports_cli(path), source
    fine = tmp_path / 'fine.py'
    fine.write_text('from matrix_core.calib import scene\nimport matrix_core.client_side\n')
    assert not imports_cli(fine)


def test_no_core_module_imports_the_cli():
    files = sorted(p for p in CORE.rglob('*.py') if 'cli' not in p.relative_to(CORE).parts[:1])
    assert len(files) > 10
    offenders = [str(p.relative_to(CORE)) for p in files if imports_cli(p)]
    assert not offenders, f'core modules outside matrix_core/cli import the CLI: {offenders}'
