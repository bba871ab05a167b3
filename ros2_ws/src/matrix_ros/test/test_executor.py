"""The executor the node processes spin (``matrix_ros.executor``): rclpy's EventsExecutor by default,
delivering every message of many subscriptions and running timers; ``MATRIX_ROS_EXECUTOR`` selects it.
Real rclpy, one process, messages over DDS."""

import time

import pytest
import rclpy
import rclpy.executors
from std_msgs.msg import Header

from matrix_ros.executor import EXECUTOR_VARIABLE, make_executor
from matrix_ros.qos import publisher_qos, qos_by_name

pytestmark = pytest.mark.ros

TOPICS, MESSAGES = 30, 5  # as many subscriptions as the recorder's per-view topics


@pytest.mark.parametrize('name', ['events', 'single'])
def test_every_message_of_many_subscriptions_and_the_timer_arrive(monkeypatch, name):
    monkeypatch.setenv(EXECUTOR_VARIABLE, name)
    rclpy.init()
    try:
        executor = make_executor()
        assert isinstance(executor, rclpy.executors.SingleThreadedExecutor) == (name == 'single')
        node = rclpy.create_node(f'executor_test_{name}')
        executor.add_node(node)
        received, ticks = {}, []
        pubs = [node.create_publisher(Header, f'/executor_test_{name}/t{i}', publisher_qos()) for i in range(TOPICS)]
        for i in range(TOPICS):
            node.create_subscription(
                Header,
                f'/executor_test_{name}/t{i}',
                lambda m, i=i: received.setdefault(i, []).append(m.frame_id),
                qos_by_name('history', depth=MESSAGES),
            )
        node.create_timer(0.05, lambda: ticks.append(time.monotonic()))
        end = time.monotonic() + 10
        while any(p.get_subscription_count() == 0 for p in pubs) and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        for k in range(MESSAGES):
            for p in pubs:
                p.publish(Header(frame_id=str(k)))
        while (sum(map(len, received.values())) < TOPICS * MESSAGES or len(ticks) < 2) and time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        assert received == {i: [str(k) for k in range(MESSAGES)] for i in range(TOPICS)}
        assert len(ticks) >= 2
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.try_shutdown()


def test_an_unknown_executor_is_named_in_the_error(monkeypatch):
    monkeypatch.setenv(EXECUTOR_VARIABLE, 'multi')
    with pytest.raises(ValueError, match=f"{EXECUTOR_VARIABLE}='multi'"):
        make_executor()
