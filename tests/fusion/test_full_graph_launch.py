"""The full-graph launch file cannot run here (no `launch` package in the pip environment): check that it
parses, that every node it starts is an installed executable, and that its launch arguments are declared
with descriptions and used consistently."""

import ast
from pathlib import Path

import pytest

LAUNCH = Path(__file__).resolve().parents[2] / 'ros2_ws/src/matrix_bringup/launch/full_graph.launch.py'


def _calls(tree, name):
    return [n for n in ast.walk(tree) if isinstance(n, ast.Call) and getattr(n.func, 'id', None) == name]


def _kw(call, key):
    for k in call.keywords:
        if k.arg == key and isinstance(k.value, ast.Constant):
            return k.value.value
    return None


def test_launch_file_parses_and_names_installed_nodes(node_executable):
    tree = ast.parse(LAUNCH.read_text(), str(LAUNCH))
    nodes = {(_kw(c, 'package'), _kw(c, 'executable')) for c in _calls(tree, 'Node')}
    assert nodes == {('matrix_calib', 'calib'), ('matrix_register', 'register'), ('matrix_bev_tracker', 'fuse'),
                     ('matrix_ros', 'bag_player'), ('matrix_ros', 'recorder')}
    for package, executable in nodes:
        assert node_executable(package, executable).is_file()


def test_launch_arguments_are_declared_and_described():
    tree = ast.parse(LAUNCH.read_text())
    declared = {}
    for call in _calls(tree, 'DeclareLaunchArgument'):
        declared[call.args[0].value] = _kw(call, 'description')
    assert all(declared.values()), declared
    used = {c.args[0].value for c in _calls(tree, 'LaunchConfiguration') if isinstance(c.args[0], ast.Constant)}
    used |= {c.args[1].value for c in _calls(tree, '_arg')}
    assert used <= set(declared), used - set(declared)
    assert {'bag', 'dataset', 'views', 'checkpoint', 'record', 'lockstep'} <= set(declared)


@pytest.mark.parametrize('package, name', [('matrix_bev_tracker', 'fuse.yaml')])
def test_fuse_config_matches_the_node_parameters(install_dir, package, name):
    """Every parameter in config/fuse.yaml is a FuseNodeSettings field with the same default, and every
    parameter of the node itself (not the tracker's, which grow elsewhere) is in the file."""
    import yaml

    from matrix_core.settings import settings_fields
    from matrix_bev_tracker.fuse_node import FuseNodeSettings

    params = yaml.safe_load((install_dir / package / 'share' / package / 'config' / name).read_text())
    params = params['fuse']['ros__parameters']
    defaults = {n: d for n, _, d, _ in settings_fields(FuseNodeSettings)}
    from matrix_core.tracking.settings import TrackerSettings
    own = set(defaults) - set(TrackerSettings.__dataclass_fields__)
    assert set(params) <= set(defaults) and own <= set(params), (set(params) - set(defaults), own - set(params))
    for key, value in params.items():
        assert value == defaults[key] or (isinstance(value, list) and list(value) == list(defaults[key])), key
