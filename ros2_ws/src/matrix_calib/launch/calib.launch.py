"""Per-drone checkerboard calibration: one ``calib`` node hosting the listed drones (or one per namespace)."""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare


def generate_launch_description():
    args = [
        DeclareLaunchArgument('config', default_value=PathJoinSubstitution(
            [FindPackageShare('matrix_calib'), 'config', 'matrix_sample.yaml']),
            description='scene YAML: boards (internal world frame), intrinsics, optional initial poses'),
        DeclareLaunchArgument('views', default_value="['D1','D2','D3','D4','D5','D6','D7','D8']",
                              description='drones hosted by this one process (topics /V/image_raw ...)'),
        DeclareLaunchArgument('prior_dataset', default_value='',
                              description='MATRIX folder whose reference/calibrations give the first prior'),
        DeclareLaunchArgument('compressed', default_value='false',
                              description='subscribe V/image/compressed instead of V/image_raw'),
        DeclareLaunchArgument('intrinsics_topic', default_value='',
                              description='per-drone CameraInfo topic under /V/ whose K, D replace the config '
                                          'intrinsics (empty = config only)'),
        DeclareLaunchArgument('qos', default_value='sensor_data',
                              description='image subscription QoS: sensor_data or reliable'),
        DeclareLaunchArgument('use_registration', default_value='false',
                              description="let each drone's registration (/V/homography from register) guide "
                                          'its calibration: about 5x less calib time'),
    ]
    node = Node(
        package='matrix_calib', executable='calib', name='calib', output='screen',
        parameters=[{'config': LaunchConfiguration('config'), 'views': LaunchConfiguration('views'),
                     'prior_dataset': LaunchConfiguration('prior_dataset'),
                     'compressed': LaunchConfiguration('compressed'), 'qos': LaunchConfiguration('qos'),
                     'intrinsics_topic': LaunchConfiguration('intrinsics_topic'),
                     'use_registration': LaunchConfiguration('use_registration')}])
    return LaunchDescription(args + [node])
