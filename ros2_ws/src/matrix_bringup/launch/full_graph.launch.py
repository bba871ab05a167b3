"""The whole live graph on a replayed sequence bag: player -> calib + register (per drone) -> fuse -> recorder.

Starts: ``bag_player`` (in lockstep with the fuse node's tracks, or at the recorded rate), ``calib`` and
``register`` (one process per drone in namespace /Dn with ``per_drone:=true``, else one process for all
drones), ``fuse`` (parameters from ``fuse_config``, homographies from register or CameraInfo from calib)
and ``recorder`` (tracks, detections, heatmap, diagnostics to ``record`` + MOT text). Score the recording
with ``matrix-tracker evaluate-recording RECORD --ground-truth BAG``. Everything runs under /clock.
Make the bag with ``matrix-tracker bag DATASET --out BAG`` (or ``matrix-tracker simulate ... --bag``).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction, SetEnvironmentVariable
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare

VIEWS = 'D1,D2,D3,D4,D5,D6,D7,D8'
RECORDED = [('/tracks', 'matrix_msgs/msg/TrackArray'), ('/detections', 'matrix_msgs/msg/TrackArray'),
            ('/bev_heatmap', 'nav_msgs/msg/OccupancyGrid'), ('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray')]


def _arg(context, name: str) -> str:
    return LaunchConfiguration(name).perform(context)


def _drone_nodes(context):
    """calib + register (one process per drone in namespace /Dn, or one for all drones), fuse and the player;
    resolved at launch time because the number of processes depends on ``views`` and ``per_drone``."""
    views = [v.strip() for v in _arg(context, 'views').split(',') if v.strip()]
    dataset, sim = LaunchConfiguration('dataset'), {'use_sim_time': True}
    calib = {'config': LaunchConfiguration('calib_config'), 'prior_dataset': dataset, 'qos': 'reliable', **sim}
    register = {'reference_dataset': dataset, **sim}
    groups = [[v] for v in views] if _arg(context, 'per_drone').lower() == 'true' else [views]
    profile = _arg(context, 'dds_profile')
    nodes = [SetEnvironmentVariable('FASTRTPS_DEFAULT_PROFILES_FILE', profile)] if profile else []
    for group in groups:
        ns = group[0] if len(groups) > 1 else ''
        nodes += [
            Node(package='matrix_calib', executable='calib', name='calib', namespace=ns, output='screen',
                 parameters=[{**calib, 'views': group}]),
            Node(package='matrix_register', executable='register', name='register', namespace=ns, output='screen',
                 parameters=[{**register, 'views': group}]),
        ]
    fuse_overrides = {'views': views, 'input_kind': LaunchConfiguration('input_kind'),
                      'checkpoint': LaunchConfiguration('checkpoint'),
                      'sync_timeout': float(_arg(context, 'sync_timeout')), **sim}
    nodes.append(Node(package='matrix_bev_tracker', executable='fuse', name='fuse', output='screen',
                      parameters=[LaunchConfiguration('fuse_config'), fuse_overrides]))
    lockstep = _arg(context, 'lockstep').lower() == 'true'
    # The player's image topics each have a calib, a register and the fuse subscriber.
    nodes.append(Node(package='matrix_ros', executable='bag_player', name='bag_player', output='screen',
                      parameters=[{'bag': LaunchConfiguration('bag'), 'rate': float(_arg(context, 'rate')),
                                   'wait_for_subscribers': 3, 'lockstep': lockstep, 'lockstep_topic': '/tracks',
                                   'lockstep_type': 'matrix_msgs/msg/TrackArray'}]))
    return nodes


def generate_launch_description():
    args = [
        DeclareLaunchArgument('bag', description='sequence bag to replay (matrix-tracker bag DATASET --out BAG)'),
        DeclareLaunchArgument('dataset', description='the MATRIX-format folder the bag came from (reference/ '
                              'images and calibrations for register and the first calib prior)'),
        DeclareLaunchArgument('views', default_value=VIEWS, description='drones, comma separated'),
        DeclareLaunchArgument('per_drone', default_value='true',
                              description='true: one calib and one register process per drone in namespace /Dn; '
                                          'false: one process each for all drones'),
        DeclareLaunchArgument('calib_config', default_value=PathJoinSubstitution(
            [FindPackageShare('matrix_calib'), 'config', 'matrix_sample.yaml']),
            description='calibration scene YAML (boards, intrinsics), e.g. sim_complex.yaml for simulated bags'),
        DeclareLaunchArgument('fuse_config', default_value=PathJoinSubstitution(
            [FindPackageShare('matrix_bev_tracker'), 'config', 'fuse.yaml']), description='fuse node parameters'),
        DeclareLaunchArgument('input_kind', default_value='homography',
                              description='fuse on register\'s homographies or on calib\'s camera_info'),
        DeclareLaunchArgument('checkpoint', default_value='',
                              description='BEV checkpoint (.pt); empty: the shipped complex_quick.pt'),
        DeclareLaunchArgument('sync_timeout', default_value='5.0',
                              description='seconds the fuse node waits for a late drone before fusing without it'),
        DeclareLaunchArgument('lockstep', default_value='true',
                              description='true: the next frame leaves the bag after the fuse node published tracks '
                                          '(deterministic); false: recorded timing scaled by rate'),
        DeclareLaunchArgument('rate', default_value='1.0', description='replay speed without lockstep'),
        DeclareLaunchArgument('dds_profile', default_value='',
                              description='Fast DDS profile for every node, e.g. matrix_bringup/config/fastdds.xml '
                                          '(large images in shared memory, 0.1 s heartbeat); empty: the environment\'s'),
        DeclareLaunchArgument('record', default_value='out/full_graph/recording',
                              description='bag folder the recorder creates (must not exist); MOT text beside it'),
    ]
    recorder = Node(package='matrix_ros', executable='recorder', name='recorder', output='screen',
                    parameters=[{'out': LaunchConfiguration('record'), 'topics': [t for t, _ in RECORDED],
                                 'types': [m for _, m in RECORDED], 'tracks_topic': '/tracks',
                                 'use_sim_time': True}])
    return LaunchDescription(args + [OpaqueFunction(function=_drone_nodes), recorder])
