"""A player starts only once its awaited subscriptions have stayed matched for a while
(``matrix_ros.connect.SubscribersReady``): discovery runs each way separately, so a subscription the
publisher already counts may not yet accept its messages. Real rclpy publishers and subscriptions."""

import time

import pytest
import rclpy
from std_msgs.msg import Header

from matrix_ros.connect import SubscribersReady
from matrix_ros.qos import publisher_qos

pytestmark = pytest.mark.ros


def _spin_until(node, condition, timeout_s=10.0):
    end = time.monotonic() + timeout_s
    while not condition() and time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
    assert condition()


def test_ready_only_after_the_subscriptions_stayed_matched_for_the_settle_time():
    rclpy.init()
    try:
        node = rclpy.create_node('subscribers_ready_test')
        pub = node.create_publisher(Header, '/subscribers_ready_test/a', publisher_qos())
        ready = SubscribersReady({'a': pub}, need=1, settle_s=0.5)
        assert not ready.ready(0.0) and ready.short() == {'a': 0}
        sub = node.create_subscription(Header, '/subscribers_ready_test/a', lambda m: None, 10)
        _spin_until(node, lambda: pub.get_subscription_count() == 1)
        assert ready.short() == {}
        assert not ready.ready(10.0)  # matched just now: the settle time starts
        assert not ready.ready(10.4)
        assert ready.ready(10.5)
        node.destroy_subscription(sub)  # a subscription gone restarts the wait
        _spin_until(node, lambda: pub.get_subscription_count() == 0)
        assert not ready.ready(11.0)
        assert SubscribersReady({'a': pub}, need=0).ready(0.0)  # nothing awaited: ready at once
        node.destroy_node()
    finally:
        rclpy.shutdown()
