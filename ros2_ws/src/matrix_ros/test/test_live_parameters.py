"""matrix_ros.params.declare_settings: parameters named ``live`` change the node's settings while it runs
(validated by the settings dataclass); every other parameter is read-only and says so."""

from dataclasses import dataclass, field

import pytest
import rclpy
from rclpy.parameter import Parameter

from matrix_ros.params import SettingsNode, declare_settings


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
    node = SettingsNode('live_parameters_test')
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


def test_an_unknown_parameter_is_an_error_naming_it_and_the_valid_ones():
    """A mistyped ``-p``: rclpy would ignore it silently; declare_settings names it, the closest
    parameter and all of the node's."""
    rclpy.init(args=['test', '--ros-args', '-p', 'gap_z:=1.0', '-p', 'use_sim_time:=true'])
    node = SettingsNode('unknown_parameter_test')
    try:
        with pytest.raises(
            ValueError,
            match=r"unknown parameter\(s\) 'gap_z' \(did you mean 'gap_s'\?\); its "
            r"parameters are: .*gap_s.*use_sim_time, views",
        ):
            declare_settings(node, _Settings)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def test_given_values_are_typed_by_the_fields():
    """``-p gap_s:=3`` is read as an integer by rclpy: the float field takes 3.0; a parameter of another node
    of the process (``shared``) is accepted and is not a parameter of this one."""
    rclpy.init(args=['test', '--ros-args', '-p', 'gap_s:=3', '-p', 'views:=[D2, D4]', '-p', 'other:=1'])
    node = SettingsNode('typed_parameter_test')
    try:
        settings = declare_settings(node, _Settings, shared=('other',))
        assert settings.gap_s == 3.0 and type(settings.gap_s) is float and settings.views == ['D2', 'D4']
        assert node.get_parameter('gap_s').type_ == Parameter.Type.DOUBLE
        assert not node.has_parameter('other')
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def test_a_value_of_the_wrong_type_is_an_error_naming_it():
    rclpy.init(args=['test', '--ros-args', '-p', 'views:=D2'])
    node = SettingsNode('wrong_type_test')
    try:
        with pytest.raises(ValueError, match=r"wrong_type_test: parameter 'views' is a list of str, got 'D2'"):
            declare_settings(node, _Settings)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def test_a_plain_node_cannot_declare_settings():
    """A plain rclpy node keeps what was given to it private: declare_settings could not check it."""
    from rclpy.node import Node

    rclpy.init()
    node = Node('plain_node_test')
    try:
        with pytest.raises(TypeError, match='SettingsNode'):
            declare_settings(node, _Settings)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def test_a_node_given_an_unknown_parameter_does_not_start(node_executable, tmp_path):
    """The same from the command line of a real node (the recorder starts in about a second)."""
    import subprocess

    run = subprocess.run(
        [
            str(node_executable('matrix_ros', 'recorder')),
            '--ros-args',
            '-p',
            f'out:={tmp_path / "r"}',
            '-p',
            'flush_period:=0.5',
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=60,
    )
    assert (
        run.returncode != 0 and "unknown parameter(s) 'flush_period' (did you mean 'flush_period_s'?)" in run.stdout
    ), run.stdout[-2000:]
    assert not (tmp_path / 'r').exists()
