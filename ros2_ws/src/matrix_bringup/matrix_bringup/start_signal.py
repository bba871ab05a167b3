"""``python -m matrix_bringup.start_signal --players N --lead S``: the common start of the bag players of a
distributed run (their ``start_topic``). Waits until ``N`` players subscribed ``topics.PLAYER_START_TOPIC``
(each does once its own subscribers matched: it is ready to play), then publishes one std_msgs/Header whose
stamp is the wall time ``S`` seconds later, when frame 0 leaves every host; then stays up until SIGINT/SIGTERM
(its transient-local message with it). The lead only covers the delivery of that message to players that are
ready, not their start-up, so however long the hosts take to start no player starts late."""

import argparse
import sys
import time

import rclpy
import rclpy.executors
from std_msgs.msg import Header

from matrix_core import topics
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.executor import spin_until
from matrix_ros.qos import publisher_qos


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument('--players', type=int, required=True, help='bag players to wait for')
    p.add_argument('--lead', type=float, default=5.0, help='seconds from all players ready to frame 0')
    args = p.parse_args(argv)
    rclpy.init()
    node = rclpy.create_node('start_signal')
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    pub = node.create_publisher(Header, topics.PLAYER_START_TOPIC, publisher_qos())
    try:
        spin_until(executor, lambda: pub.get_subscription_count() >= args.players, 0.1)
        if rclpy.ok():
            start_at = time.time() + args.lead
            pub.publish(Header(stamp=seconds_to_stamp(start_at)))
            print(f'{args.players} players ready; frame 0 at {start_at:.3f}', flush=True)
            spin_until(executor)  # SIGTERM and SIGINT through rclpy's handlers end it
    except KeyboardInterrupt:
        pass
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
