"""Publish a MATRIX-format folder as per-view image and ground-truth CameraInfo topics."""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    args = [
        DeclareLaunchArgument('dataset', description='MATRIX, Wildtrack or MultiviewX folder to publish'),
        DeclareLaunchArgument('rate', default_value='1.0', description='playback speed factor'),
        DeclareLaunchArgument('loop', default_value='false', description='start again after the last frame'),
    ]
    player = Node(
        package='matrix_ros', executable='dataset_player', name='dataset_player', output='screen',
        parameters=[{'dataset': LaunchConfiguration('dataset'), 'rate': LaunchConfiguration('rate'),
                     'loop': LaunchConfiguration('loop')}])
    return LaunchDescription(args + [player])
