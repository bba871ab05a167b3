"""Register each drone's image to its reference image and publish /<view>/homography."""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    config = os.path.join(get_package_share_directory('matrix_register'), 'config', 'register.yaml')
    args = [
        DeclareLaunchArgument('params_file', default_value=config,
                              description='YAML with the node parameters (defaults: config/register.yaml)'),
        DeclareLaunchArgument('reference_dataset', default_value='',
                              description="MATRIX folder whose reference/ gives each drone's reference image "
                                          'and calibration; empty = first frame with a CameraInfo'),
        DeclareLaunchArgument('backend', default_value='sift',
                              description='feature backend: sift, gftt_affnet_hardnet (needs '
                                          'checkpoint_liberty_with_aug.pth), gftt_affnet_hardtfeat, gftt_affnet_sift'),
        DeclareLaunchArgument('scale', default_value='0.25',
                              description='image scale for feature extraction (0.25 = 480x270)'),
    ]
    node = Node(
        package='matrix_register', executable='register', name='register', output='screen',
        parameters=[LaunchConfiguration('params_file'),
                    {'reference_dataset': LaunchConfiguration('reference_dataset'),
                     'backend': LaunchConfiguration('backend'),
                     'scale': LaunchConfiguration('scale')}])
    return LaunchDescription(args + [node])
