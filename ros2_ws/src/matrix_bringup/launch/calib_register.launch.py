"""Replay a MATRIX-format folder through per-drone calibration and registration, scored live.

Starts: dataset_player (images + ground-truth CameraInfo), calib (all drones in one process),
register (all drones in one process) and graph_monitor (prints the scores and writes a picture).
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
        DeclareLaunchArgument('dataset', description='MATRIX-format folder to replay (with reference/)'),
        DeclareLaunchArgument('views', default_value=VIEWS, description='drones to run'),
        DeclareLaunchArgument('rate', default_value='0.5', description='playback speed factor (1 = 2 frames/s)'),
        DeclareLaunchArgument('calib_config', default_value=PathJoinSubstitution(
            [FindPackageShare('matrix_calib'), 'config', 'matrix_sample.yaml']),
            description='calibration scene YAML (boards, intrinsics)'),
        DeclareLaunchArgument('out_dir', default_value='out/graph_monitor',
                              description='where the monitor writes its table and picture'),
    ]
    nodes = [
        Node(package='matrix_calib', executable='calib', name='calib', output='screen',
             parameters=[{'views': views, 'config': LaunchConfiguration('calib_config'),
                          'prior_dataset': dataset, 'qos': 'reliable'}]),
        Node(package='matrix_register', executable='register', name='register', output='screen',
             parameters=[{'views': views, 'reference_dataset': dataset}]),
        Node(package='matrix_bringup', executable='graph_monitor', name='graph_monitor', output='screen',
             parameters=[{'views': views, 'out_dir': LaunchConfiguration('out_dir')}]),
        Node(package='matrix_ros', executable='dataset_player', name='dataset_player', output='screen',
             parameters=[{'dataset': dataset, 'views': views, 'rate': LaunchConfiguration('rate'),
                          'wait_for_subscribers': 3}]),
    ]
    return LaunchDescription(args + nodes)
