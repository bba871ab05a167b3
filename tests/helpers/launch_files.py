"""Run a launch file's description with the real ``launch`` / ``launch_ros`` packages (built by
scripts/build_cli.sh, or a ROS install), without starting any process: its declared arguments, and the
actions its ``OpaqueFunction`` returns for given arguments (``launch_ros`` ``Node`` s, normalised and
checked by launch_ros itself). Importable as ``launch_files`` (the root conftest.py puts this folder on
``sys.path``). What the launched processes then do is tested with ``ros2 launch`` (tests/system/).
"""

from dataclasses import dataclass
from pathlib import Path

from launch import LaunchContext
from launch.actions import OpaqueFunction
from launch.launch_description_sources.python_launch_file_utilities import (
    get_launch_description_from_python_launch_file,
)
from launch.utilities import perform_substitutions
from launch_ros.actions import Node
from launch_ros.utilities import evaluate_parameters


def load(path):
    """The ``LaunchDescription`` of the Python launch file at ``path``."""
    return get_launch_description_from_python_launch_file(str(path))


def declared_arguments(description) -> dict:
    """name -> (default as text, or None when the argument is required; description)."""
    context = LaunchContext()
    return {
        a.name: (None if a.default_value is None else perform_substitutions(context, a.default_value), a.description)
        for a in description.get_launch_arguments()
    }


@dataclass
class LaunchedNode:
    """What a ``launch_ros`` ``Node`` action will start: ``parameters`` as launch passes them, parameter file
    paths (str) and dicts of typed values (``launch_ros.utilities.evaluate_parameters``; arrays as lists)."""

    package: str
    executable: str
    name: str  # as given to Node (not the full name; Node.UNSPECIFIED_NODE_NAME when none)
    namespace: str  # '' when none
    parameters: list
    remappings: dict  # '-r' rules: source -> destination
    prefix: str  # command words before the executable ('' when none), e.g. 'nice -n 10'


def launch(description, **arguments) -> list:
    """The actions of the description's ``OpaqueFunction`` with the declared defaults, ``arguments`` replacing
    them; each ``launch_ros`` ``Node`` as a :class:`LaunchedNode` (the others as they are)."""
    values = {name: default for name, (default, _) in declared_arguments(description).items()}
    values.update(arguments)
    missing = [name for name, value in values.items() if value is None]
    assert not missing, f'required launch arguments not given: {missing}'
    context = LaunchContext()
    context.launch_configurations.update(values)
    opaque = next(e for e in description.entities if isinstance(e, OpaqueFunction))
    return [_launched(a, context) if isinstance(a, Node) else a for a in opaque.execute(context)]


def _launched(node: Node, context) -> LaunchedNode:
    node._perform_substitutions(context)  # launch_ros keeps what it was given private; this resolves it
    namespace = node.expanded_node_namespace.strip('/')
    parameters = evaluate_parameters(context, node._Node__parameters)
    return LaunchedNode(
        node.node_package,
        node.node_executable,
        node.node_name.rsplit('/', 1)[-1],
        '' if namespace == Node.UNSPECIFIED_NODE_NAMESPACE.strip('/') else namespace,
        [
            str(p) if isinstance(p, Path) else {k: list(v) if isinstance(v, tuple) else v for k, v in p.items()}
            for p in parameters
        ],
        dict(node.expanded_remapping_rules or []),
        perform_substitutions(context, node.process_description.prefix or []),
    )
