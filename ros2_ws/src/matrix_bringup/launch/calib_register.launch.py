"""Replay a sequence bag through per-drone calibration and registration, scored live (what `make demo` runs).

Starts: bag_player (in lockstep with the monitor), calib (all drones in one process), register (all
drones in one process) and graph_monitor (prints the scores, writes a picture, announces finished frames).
Make the bag with `matrix-tracker bag DATASET --out BAG`.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare

VIEWS = "['D1','D2','D3','D4','D5','D6','D7','D8']"


def generate_launch_description():
    dataset = LaunchConfiguration('dataset')
    views = LaunchConfiguration('views')
    args = [
        DeclareLaunchArgument('bag', description='sequence bag to replay (matrix-tracker bag DATASET --out BAG)'),
        DeclareLaunchArgument('dataset', description='the MATRIX-format folder the bag came from (its reference/ '
                              'gives the registration references and the first calibration prior)'),
        DeclareLaunchArgument('frames', default_value='0', description='frames in the bag (the monitor stops after them)'),
        DeclareLaunchArgument('views', default_value=VIEWS, description='drones to run'),
        DeclareLaunchArgument('calib_config', default_value=PathJoinSubstitution(
            [FindPackageShare('matrix_calib'), 'config', 'matrix_sample.yaml']),
            description='calibration scene YAML (boards, intrinsics)'),
        DeclareLaunchArgument('out_dir', default_value='out/graph_monitor',
                              description='where the monitor writes its table and picture'),
    ]
    nodes = [
        Node(package='matrix_calib', executable='calib', name='calib', output='screen',
             parameters=[{'views': views, 'config': LaunchConfiguration('calib_config'),
                          'prior_dataset': dataset, 'qos': 'reliable', 'use_registration': True}]),
        Node(package='matrix_register', executable='register', name='register', output='screen',
             parameters=[{'views': views, 'reference_dataset': dataset}]),
        Node(package='matrix_bringup', executable='graph_monitor', name='graph_monitor', output='screen',
             parameters=[{'views': views, 'out_dir': LaunchConfiguration('out_dir'),
                          'expected_frames': LaunchConfiguration('frames')}]),
        Node(package='matrix_ros', executable='bag_player', name='bag_player', output='screen',
             parameters=[{'bag': LaunchConfiguration('bag'), 'wait_for_subscribers': 3, 'lockstep': True,
                          'lockstep_topic': '/graph_monitor/frame_done', 'lockstep_type': 'std_msgs/msg/Header'}]),
    ]
    return LaunchDescription(args + nodes)
