"""``python -m matrix_bringup.discovery_server``: the Fast DDS discovery server of a deployment, for links that
do not pass multicast (run it on the ground station, before the rest; every other process uses
config/fastdds_client.xml). A ROS process whose one DDS participant is the server: it loads
config/fastdds_server.xml (or ``--profile``) itself and leaves discovery to that file
(``ROS_AUTOMATIC_DISCOVERY_RANGE=SYSTEM_DEFAULT``: rmw's ``LOCALHOST`` fails to create a server). It needs
nothing but the rclpy and rmw_fastrtps wheels; the ``fastdds discovery`` tool of those wheels cannot find its
binary (see the profile for running that binary by hand)."""

import argparse
import os
import sys

from matrix_bringup.graph import share_file


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        '--profile',
        default=None,
        help='Fast DDS profile of the server (default: share/matrix_bringup/config/fastdds_server.xml)',
    )
    args = parser.parse_args(argv)
    # Read by Fast DDS when rclpy creates the participant, so set before rclpy.init
    os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = args.profile or share_file(
        'matrix_bringup', 'config', 'fastdds_server.xml'
    )
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'SYSTEM_DEFAULT'
    os.environ.pop('ROS_DISCOVERY_SERVER', None)  # it would make this participant a client

    import rclpy

    from matrix_ros.params import spin_nodes  # imported after the environment is set: it loads rclpy

    def server():
        node = rclpy.create_node('discovery_server')
        node.get_logger().info(f"discovery server up ({os.environ['FASTRTPS_DEFAULT_PROFILES_FILE']})")
        return node

    return spin_nodes([server], [sys.argv[0]], description=__doc__)


if __name__ == '__main__':
    sys.exit(main())
