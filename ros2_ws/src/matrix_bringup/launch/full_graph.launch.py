"""The whole live graph on a replayed sequence bag: player -> calib + register (per drone) -> fuse -> recorder,
optionally graph_monitor.

The processes and their parameters come from ``matrix_bringup.graph.graph_nodes``: the same list that
``run_graph`` starts where there is no ``ros2 launch``. The launch arguments are the fields of
``matrix_bringup.graph.GraphSettings`` (same names, defaults and descriptions as ``run_graph``'s flags), plus
``exit_at_end``: the replay ends by itself (``matrix_bringup.replay_end``).

    ros2 launch matrix_bringup full_graph.launch.py bag:=BAG dataset:=DIR [record:=OUT/recording] [monitor:=true]
    ros2 launch matrix_bringup full_graph.launch.py bag:=BAG site:=SITE.yaml   (each drone's references: the site's)

Make the bag with ``matrix-tracker bag DATASET --out BAG`` (or ``matrix-tracker simulate ... --bag``); score
the recording with ``matrix-tracker evaluate-recording OUT/recording --ground-truth BAG``.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, LogInfo, OpaqueFunction, SetEnvironmentVariable
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from matrix_bringup.drone_check import left_out_text, without_unreadable_drones
from matrix_bringup.graph import GraphSettings, graph_nodes, monitor_skipped
from matrix_bringup.replay_end import ReplayEnd
from matrix_ros.launch_settings import declare_arguments, settings_from_launch

EXIT_AT_END = DeclareLaunchArgument(
    'exit_at_end',
    default_value='true',
    description=(
        'true: once the player has played the bag and the last frame is processed (and the monitor, if any, has '
        'written its scores) every node is stopped and the launch exits: 0, or 1 when lockstep timed out for '
        'some frame, a node died or a drone was left out at start (its reference unreadable; the others ran); '
        'false: the nodes keep running after the replay'
    ),
)


def _graph(context):
    """Resolved at launch time: the number of processes depends on ``views`` and ``drones_per_process``."""
    settings = settings_from_launch(GraphSettings, context, other_arguments=['exit_at_end'])
    settings, left_out = without_unreadable_drones(settings)  # a drone that cannot start: the others run
    actions = (
        [SetEnvironmentVariable('FASTRTPS_DEFAULT_PROFILES_FILE', settings.dds_profile)] if settings.dds_profile else []
    )
    if left_out:
        actions.append(LogInfo(msg=f'full_graph: {left_out_text(left_out)}; the other drones run'))
    if skipped := monitor_skipped(settings):
        actions.append(LogInfo(msg=f'full_graph: {skipped}'))
    specs = graph_nodes(settings)
    nodes = {
        spec.label: Node(
            package=spec.package,
            executable=spec.executable,
            name=spec.name if spec.renamed else None,
            namespace=spec.namespace or None,
            remappings=list(spec.remaps.items()) or None,
            output='screen',
            prefix=' '.join(spec.prefix) or None,
            parameters=[*spec.param_files, spec.parameters],
        )
        for spec in specs
    }
    if IfCondition(LaunchConfiguration('exit_at_end')).evaluate(context):
        monitor = next((s.label for s in specs if s.executable == 'graph_monitor'), None)
        actions += ReplayEnd(
            nodes,
            player=specs[-1].label,
            monitor=monitor,
            monitor_timeout_s=settings.lockstep_timeout,
            left_out=left_out,
        ).handlers()
    return actions + list(nodes.values())


def generate_launch_description():
    return LaunchDescription(declare_arguments(GraphSettings) + [EXIT_AT_END, OpaqueFunction(function=_graph)])
