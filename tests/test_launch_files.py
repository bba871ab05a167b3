"""One source of wiring: every launch file's arguments are generated from the settings of what it starts, and
the ROS parameter files under config/ list only values that differ from those settings' defaults.

The launch files are evaluated here with the real launch API, without starting processes (tests/helpers/
launch_files.py); full_graph.launch.py with the graph in tests/fusion/test_full_graph_launch.py, and every
launch file started for real with `ros2 launch` in tests/system/test_ros2_launch.py.
"""

from pathlib import Path

import pytest
import yaml

from launch_files import declared_arguments, launch, load
from matrix_core.settings import setting_to_string, settings_fields, settings_from_strings

SRC = Path(__file__).resolve().parents[1] / 'ros2_ws' / 'src'
EIGHT = [f'D{i}' for i in range(1, 9)]


def _calib():
    from matrix_calib.settings import CalibNodeSettings

    return CalibNodeSettings


def _register():
    from matrix_register.settings import RegisterNodeSettings

    return RegisterNodeSettings


def _dataset_player():
    from matrix_ros.dataset_player import DatasetPlayerSettings

    return DatasetPlayerSettings


def _fuse():
    from matrix_bev_tracker.settings import FuseNodeSettings

    return FuseNodeSettings


# launch file -> (package, executable, settings class, launch defaults that differ from the settings', required)
NODE_LAUNCH_FILES = {
    'matrix_calib/launch/calib.launch.py': ('matrix_calib', 'calib', _calib, {'views': EIGHT}, ()),
    'matrix_register/launch/register.launch.py': ('matrix_register', 'register', _register, {'views': EIGHT}, ()),
    'matrix_ros/launch/dataset_player.launch.py': ('matrix_ros', 'dataset_player', _dataset_player, {}, ('dataset',)),
}
GRAPH_LAUNCH_FILES = {'matrix_bringup/launch/full_graph.launch.py'}
# ROS parameter files -> the settings of the node they are given to
PARAMETER_FILES = {'matrix_bev_tracker/config/fuse.yaml': _fuse, 'matrix_register/config/register.yaml': _register}


def test_every_launch_file_is_tested_here_or_with_the_graph():
    found = {str(p.relative_to(SRC)) for p in SRC.glob('*/launch/*.launch.py')}
    assert found == set(NODE_LAUNCH_FILES) | GRAPH_LAUNCH_FILES


@pytest.mark.parametrize('path', sorted(NODE_LAUNCH_FILES))
def test_node_launch_file_arguments_are_the_node_settings(path):
    package, executable, settings_class, defaults, required = NODE_LAUNCH_FILES[path]
    cls = settings_class()
    description = load(SRC / path)
    declared = declared_arguments(description)
    fields = {name: (default, help_text) for name, _, default, help_text in settings_fields(cls)}
    assert set(declared) == set(fields)
    for name, (default_text, description_text) in declared.items():
        assert description_text == fields[name][1] and description_text, name
        if name in required:
            assert default_text is None, name
        else:
            assert default_text == setting_to_string(defaults.get(name, fields[name][0])), name

    given = {name: 'x' for name in required}
    actions = launch(description, **given)
    (node,) = actions
    assert (node.package, node.executable, node.name) == (package, executable, executable)
    (params,) = node.parameters
    expected = settings_from_strings(cls, {**{n: setting_to_string(v) for n, v in defaults.items()}, **given})
    for name in fields:  # every value typed as the node declares it; an empty list is the unset default
        value = getattr(expected, name)
        if isinstance(value, (list, tuple)) and not value:
            assert name not in params, name
        else:
            value = list(value) if isinstance(value, tuple) else value
            assert params[name] == value and type(params[name]) is type(value), name  # 1 is no double


def test_launch_arguments_are_parsed_and_validated_by_the_settings():
    description = load(SRC / 'matrix_calib/launch/calib.launch.py')
    (node,) = launch(description, views='[D3, D5]', compressed='true', registration_wait_s='2')
    params = node.parameters[0]
    assert params['views'] == ['D3', 'D5'] and params['compressed'] is True and params['registration_wait_s'] == 2.0
    with pytest.raises(ValueError, match='fastest'):
        launch(description, qos='fastest')


@pytest.mark.parametrize('path', sorted(PARAMETER_FILES))
def test_parameter_files_list_only_values_that_differ_from_the_defaults(path):
    """Keys are the node's parameters; each value differs from its default (a default repeated here would
    hide a later change of the default)."""
    ((key, body),) = yaml.safe_load((SRC / path).read_text()).items()
    assert key == '/**', path
    params = body['ros__parameters'] or {}
    defaults = {name: default for name, _, default, _ in settings_fields(PARAMETER_FILES[path]())}
    assert set(params) <= set(defaults), set(params) - set(defaults)
    for name, value in params.items():
        default = defaults[name]
        assert value != (list(default) if isinstance(default, tuple) else default), f'{path}: {name} is the default'


def test_every_parameter_file_is_checked():
    """Files under config/ with ros__parameters are in PARAMETER_FILES; the rest are calibration scenes
    (their own boards, or a ``site:`` whose boards they take)."""
    for path in SRC.glob('*/config/*.yaml'):
        name = str(path.relative_to(SRC))
        if name not in PARAMETER_FILES:
            scene = yaml.safe_load(path.read_text())
            assert name.startswith('matrix_calib/config/') and ('boards' in scene or 'site' in scene), name
