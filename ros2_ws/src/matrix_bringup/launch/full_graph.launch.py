"""The whole live graph on a replayed sequence bag: player -> calib + register (per drone) -> fuse -> recorder,
optionally graph_monitor.

The processes and their parameters come from ``matrix_bringup.graph.graph_nodes``: the same list that
``run_graph`` starts where there is no ``ros2 launch``. The launch arguments are the fields of
``matrix_bringup.graph.GraphSettings`` (same names, defaults and descriptions as ``run_graph``'s flags).

    ros2 launch matrix_bringup full_graph.launch.py bag:=BAG dataset:=DIR [record:=OUT/recording] [monitor:=true]

Make the bag with ``matrix-tracker bag DATASET --out BAG`` (or ``matrix-tracker simulate ... --bag``); score
the recording with ``matrix-tracker evaluate-recording OUT/recording --ground-truth BAG``.
"""

from launch import LaunchDescription
from launch.actions import OpaqueFunction, SetEnvironmentVariable
from launch_ros.actions import Node

from matrix_bringup.graph import GraphSettings, graph_nodes
from matrix_ros.launch_settings import declare_arguments, settings_from_launch


def _graph(context):
    """Resolved at launch time: the number of processes depends on ``views`` and ``drones_per_process``."""
    settings = settings_from_launch(GraphSettings, context)
    actions = [SetEnvironmentVariable('FASTRTPS_DEFAULT_PROFILES_FILE', settings.dds_profile)] \
        if settings.dds_profile else []
    for node in graph_nodes(settings):
        actions.append(Node(package=node.package, executable=node.executable, name=node.name,
                            namespace=node.namespace or None, output='screen',
                            parameters=[*node.param_files, node.parameters]))
    return actions


def generate_launch_description():
    return LaunchDescription(declare_arguments(GraphSettings) + [OpaqueFunction(function=_graph)])
