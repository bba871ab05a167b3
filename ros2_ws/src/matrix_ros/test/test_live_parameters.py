"""matrix_ros.params.declare_settings: parameters named ``live`` change the node's settings while it runs
(validated by the settings dataclass); every other parameter is read-only and says so."""

from dataclasses import dataclass, field

import pytest
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter

from matrix_ros.params import declare_settings


@dataclass
class _Settings:
    gap_s: float = field(default=5.0, metadata={'help': 'a gap'})
    views: list[str] = field(default_factory=list, metadata={'help': 'drones'})

    def __post_init__(self):
        if self.gap_s <= 0:
            raise ValueError('gap_s must be > 0')


@pytest.fixture
def node():
    rclpy.init()
    node = Node('live_parameters_test')
    node.settings = declare_settings(node, _Settings, live=('gap_s',))
    yield node
    node.destroy_node()
    rclpy.try_shutdown()


def test_live_parameter_changes_the_settings(node):
    (result,) = node.set_parameters([Parameter('gap_s', value=2.5)])
    assert result.successful and node.settings.gap_s == 2.5
    (result,) = node.set_parameters([Parameter('gap_s', value=-1.0)])
    assert not result.successful and 'gap_s must be > 0' in result.reason
    assert node.settings.gap_s == 2.5 and node.get_parameter('gap_s').value == 2.5


def test_other_parameters_are_read_only(node):
    (result,) = node.set_parameters([Parameter('views', value=['D1'])])
    assert not result.successful and 'read-only' in result.reason
    assert node.settings.views == []
