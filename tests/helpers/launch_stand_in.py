"""A stand-in of the parts of the ``launch`` / ``launch_ros`` API this workspace's launch files use.

`ros2 launch` cannot run here (no ``launch`` package in the pip environment), so the tests execute each
launch file against these classes, which record what they are given and check it as launch_ros would.
"""

import importlib.util
import sys
import types
from pathlib import Path


class Recorded:
    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


class LaunchConfiguration(Recorded):
    def perform(self, context):
        return context.launch_configurations[self.args[0]]


class OpaqueFunction(Recorded):
    def execute(self, context):
        return self.kwargs['function'](context)


class Node(Recorded):
    """launch_ros.actions.Node: keyword arguments only; parameters a list of file paths and dicts whose values
    launch_ros can normalise (launch_ros.utilities.normalize_parameters: str, bool, int, float, or a list of
    them, all str, all bool or all numbers; None is a TypeError there)."""

    KEYWORDS = {'executable', 'package', 'name', 'namespace', 'exec_name', 'parameters', 'remappings',
                'ros_arguments', 'arguments', 'output'}

    def __init__(self, *args, **kwargs):
        assert not args and set(kwargs) <= self.KEYWORDS, (args, set(kwargs) - self.KEYWORDS)
        for entry in kwargs.get('parameters') or []:
            if isinstance(entry, dict):
                for key, value in entry.items():
                    assert launch_parameter_ok(value), (kwargs['executable'], key, value)
            else:
                assert isinstance(entry, str) and Path(entry).is_file(), entry
        super().__init__(**kwargs)


def launch_parameter_ok(value) -> bool:
    if isinstance(value, (str, bool, int, float)):
        return True
    if not isinstance(value, (list, tuple)) or not value:
        return False
    kinds = {bool if isinstance(v, bool) else (float if isinstance(v, (int, float)) else type(v)) for v in value}
    return len(kinds) == 1 and kinds <= {str, bool, float}


def load_launch_file(monkeypatch, path):
    """The launch file at ``path`` as a module, its ``launch`` imports served by this stand-in."""
    modules = {name: types.ModuleType(name) for name in
               ('launch', 'launch.actions', 'launch.substitutions', 'launch_ros', 'launch_ros.actions')}
    modules['launch'].LaunchDescription = Recorded
    for name in ('DeclareLaunchArgument', 'SetEnvironmentVariable'):
        setattr(modules['launch.actions'], name, type(name, (Recorded,), {}))
    modules['launch.actions'].OpaqueFunction = OpaqueFunction
    modules['launch.substitutions'].LaunchConfiguration = LaunchConfiguration
    modules['launch_ros.actions'].Node = Node
    for name, module in modules.items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location(Path(path).name.replace('.', '_'), path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def declared_arguments(description) -> dict:
    """name -> keyword arguments of each DeclareLaunchArgument of a launch description."""
    return {a.args[0]: a.kwargs for a in description.args[0] if type(a).__name__ == 'DeclareLaunchArgument'}


def launch(description, **arguments) -> list:
    """The actions of the description's OpaqueFunction with the declared defaults, ``arguments`` replacing them."""
    values = {name: kw.get('default_value') for name, kw in declared_arguments(description).items()}
    values.update(arguments)
    missing = [name for name, value in values.items() if value is None]
    assert not missing, f'required launch arguments not given: {missing}'
    opaque = next(a for a in description.args[0] if isinstance(a, OpaqueFunction))
    return opaque.execute(types.SimpleNamespace(launch_configurations=values))
