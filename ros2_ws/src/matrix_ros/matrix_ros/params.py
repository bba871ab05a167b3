"""Settings dataclasses as ROS parameters (same names and defaults as the CLI flags of
:mod:`matrix_core.settings`), and the standard ``main`` of a node that takes both."""

import argparse
import array
import dataclasses
import os
import signal
import sys
import threading
import time
import typing

import rclpy
import rclpy.executors
from rcl_interfaces.msg import ParameterDescriptor, ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions
from rclpy.time_source import USE_SIM_TIME_NAME
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM
from rclpy.utilities import remove_ros_args

from matrix_core.settings import add_settings_arguments, settings_fields, settings_from_namespace
from matrix_ros.executor import make_executor, spin_until
from matrix_ros.left_out import NoDroneCanStart
from matrix_ros.site_parameter import check_site_views, site_defaults


OWN_THREAD_DRAIN_S = 10.0  # at exit, longest a node's own thread goes on with the calls handed to it

_PARAM_TYPES = {
    bool: ParameterType.PARAMETER_BOOL,
    int: ParameterType.PARAMETER_INTEGER,
    float: ParameterType.PARAMETER_DOUBLE,
    str: ParameterType.PARAMETER_STRING,
    (list, bool): ParameterType.PARAMETER_BOOL_ARRAY,
    (list, int): ParameterType.PARAMETER_INTEGER_ARRAY,
    (list, float): ParameterType.PARAMETER_DOUBLE_ARRAY,
    (list, str): ParameterType.PARAMETER_STRING_ARRAY,
}


def _type_key(typ):
    """Python annotation -> key of ``_PARAM_TYPES`` (tuples are declared as arrays)."""
    if typing.get_origin(typ) in (list, tuple):
        return (list, typing.get_args(typ)[0])
    return typ


class SettingsNode(Node):
    """A node whose parameters are a settings dataclass (:func:`declare_settings`).

    rclpy has no public getter of the parameters given to a node (``-p``, ``--params-file``; rclcpp has
    ``NodeOptions::parameter_overrides()``), so this node has rclpy declare each of them on creation
    (``automatically_declare_parameters_from_overrides``) and keeps what was given in ``given_parameters``
    (name -> value), read through the public parameter API: ``declare_settings`` then types each one by its
    field and names any the node does not have, instead of rclpy ignoring it silently."""

    def __init__(self, node_name: str, **kwargs):
        try:
            super().__init__(node_name, automatically_declare_parameters_from_overrides=True, **kwargs)
        except ValueError as exc:  # rclpy's only ValueError here: a value it cannot type
            raise ValueError(
                f'{node_name}: {exc} (a parameter given as an empty list [] has no type in rclpy: leave it out, '
                'unset is the empty default)'
            ) from exc
        self.given_parameters = {
            name: self.get_parameter(name).value
            for name in self.list_parameters([], 0).names  # depth 0 with no prefix: every declared name
            if name not in RCLPY_PARAMETERS
        }


# Declared by rclpy's Node itself, given or not: known to every node.
RCLPY_PARAMETERS = (USE_SIM_TIME_NAME, START_TYPE_DESCRIPTION_SERVICE_PARAM)


def declare_settings(node: SettingsNode, cls, defaults=None, live=(), shared=()):
    """Declare one parameter per field of ``cls`` on ``node`` and return the filled dataclass.

    ``defaults`` (an instance of ``cls``, e.g. from CLI flags) replaces the dataclass defaults; values
    given with ``--ros-args -p name:=value`` or a YAML file win over both (converted to the field's type where
    that loses nothing: ``3`` for a float is 3.0). The dataclass validates.
    ``live`` names the parameters that may change while the node runs (``ros2 param set``): a new value
    replaces ``node.settings`` by a validated copy (the node reads them from there each time); every other
    parameter is read-only, so that setting it fails with a reason instead of silently doing nothing.
    ``shared``: the parameter names of the other nodes in this process (one parameter set is given to the
    whole process, ``matrix_ros.drone_link``): not unknown here, and not parameters of this node.
    """
    if not isinstance(node, SettingsNode):
        raise TypeError(f'{node.get_name()}: declare_settings needs a matrix_ros.params.SettingsNode')
    fields = settings_fields(cls)
    names = [name for name, *_ in fields]
    given = node.given_parameters
    check_no_unknown_parameters(node, given, names, shared)
    for name in given:  # declared untyped by rclpy: declared again below, typed, or dropped (another node's)
        if not name.startswith('qos_overrides.'):
            node.undeclare_parameter(name)
    defaults, site = site_defaults(cls, defaults, given)  # the site first: the fields that follow it default to it
    values = {}
    for name, typ, default, help_text in fields:
        if defaults is not None:
            default = getattr(defaults, name)
        value = _given_value(node, name, typ, given[name]) if name in given else default
        param_type = _PARAM_TYPES[_type_key(typ)]
        descriptor = ParameterDescriptor(description=help_text, type=param_type, read_only=name not in live)
        if isinstance(value, (list, tuple)) and not value:
            # rclpy cannot infer an array type from an empty list: declare the type, unset means empty.
            node.declare_parameter(name, Parameter.Type(param_type), descriptor, ignore_override=True)
            values[name] = []
        else:
            value = list(value) if isinstance(value, (list, tuple)) else value
            values[name] = node.declare_parameter(name, value, descriptor, ignore_override=True).value
    if live:
        node.add_on_set_parameters_callback(lambda params: _set_live(node, params, live))
    settings = cls(**values)
    check_site_views(node, site, settings)
    return settings


def _given_value(node, name: str, typ, value):
    """A given parameter's value as the field's type ``typ``: as given, or an integer as a float (YAML and
    ``-p`` read ``3`` as an integer); anything else is a ValueError naming the node, the parameter and both."""
    item = typing.get_args(typ)[0] if typing.get_origin(typ) in (list, tuple) else None
    if item is None:
        values, want = [value], typ
    elif isinstance(value, (list, tuple, array.array)):
        values, want = list(value), item
    else:
        values, want = None, item
    if values is not None:
        if want is float and all(type(v) is int for v in values):
            values = [float(v) for v in values]
        if all(type(v) is want for v in values):
            return values[0] if item is None else values
    kind = f'a list of {item.__name__}' if item is not None else f'a {typ.__name__}'
    raise ValueError(f'{node.get_name()}: parameter {name!r} is {kind}, got {value!r}')


def check_no_unknown_parameters(node, given, names, shared=()) -> None:
    """ValueError naming every parameter in ``given`` (``-p``, ``--params-file``) that ``node`` does not have
    (``names``, the process's ``shared``), the closest of its own, and all of them: rclpy ignores such a value
    silently, so a typo (``sync_timout:=3.0``) would leave the default in place without a word.
    ``qos_overrides.*`` are declared later, by the publishers, and are left to rclpy."""
    import difflib

    known = sorted({*names, *RCLPY_PARAMETERS, *shared})
    unknown = sorted(n for n in given if n not in known and not n.startswith('qos_overrides.'))
    if unknown:
        hints = [
            f'{n!r} (did you mean {m[0]!r}?)' if (m := difflib.get_close_matches(n, known, 1)) else repr(n)
            for n in unknown
        ]
        raise ValueError(
            f'{node.get_name()}: unknown parameter(s) {", ".join(hints)}; its parameters are: {", ".join(known)}'
        )


def _set_live(node, params, live) -> SetParametersResult:
    """Validate the new values of ``live`` parameters with the settings dataclass, then apply them."""
    changes = {p.name: p.value for p in params if p.name in live}
    if not changes:
        return SetParametersResult(successful=True)
    try:
        settings = dataclasses.replace(node.settings, **changes)
    except (TypeError, ValueError) as exc:
        return SetParametersResult(successful=False, reason=str(exc))
    node.settings = settings
    node.get_logger().info('parameters changed: ' + ', '.join(f'{k}={v!r}' for k, v in changes.items()))
    return SetParametersResult(successful=True)


def parse_node_args(cls, argv=None, description: str = ''):
    """Parse ``argv`` (sys.argv) into (settings from CLI flags, the full argv for rclpy.init)."""
    argv = list(sys.argv if argv is None else argv)
    parser = argparse.ArgumentParser(description=description)
    add_settings_arguments(parser, cls)
    ns = parser.parse_args(remove_ros_args(argv)[1:])
    return settings_from_namespace(cls, ns), argv


def spin_node(node_factory, cls, argv=None, description: str = '', on_exit=None) -> int:
    """Standard node ``main``: CLI flags -> defaults, ``rclpy.init``, build the node, spin until SIGINT/SIGTERM.

    SIGINT and SIGTERM stop the spinning here (``on_exit(node)`` then runs, e.g. to close a bag), with the
    context still up: rclpy's own handlers would shut it down first, and a node on a thread of its own must
    still make the calls handed to it (:func:`_spin_in_thread`). So rclpy is initialised without them
    (``SignalHandlerOptions.NO``) and the two signals set a flag that :func:`matrix_ros.executor.spin_until`
    checks between slices of spinning.
    """
    cli_settings, argv = parse_node_args(cls, argv, description)
    return _spin([lambda: node_factory(cli_settings)], argv, on_exit)


def spin_nodes(node_factories, argv=None, description: str = '') -> int:
    """``main`` of a process of several nodes (``matrix_bringup.drone``): ROS parameters only (``--help``
    prints ``description``), the nodes built in order and spun by one executor, in one thread; a node whose
    ``own_thread`` is a ``matrix_ros.drone_link.OwnThread`` by its own executor in a thread of its own."""
    argv = list(sys.argv if argv is None else argv)
    argparse.ArgumentParser(description=description).parse_args(remove_ros_args(argv)[1:])
    return _spin(node_factories, argv)


def _spin(node_factories, argv, on_exit=None) -> int:
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)  # see spin_node
    stop = []  # appended to by the handlers: a list, not a threading.Event, whose lock a second signal could meet
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.append(True))
    nodes, executor, threads = [], make_executor(), []
    try:
        for factory in node_factories:
            nodes.append(factory())
            own = getattr(nodes[-1], 'own_thread', None)
            if own is None:
                executor.add_node(nodes[-1])
            else:
                threads.append(_spin_in_thread(nodes[-1], own, stop))
        spin_until(executor, lambda: bool(stop))
    except NoDroneCanStart as exc:  # bad input, not a bug: one line naming the drones, no traceback
        print(f'error: {exc}', file=sys.stderr)
        return 2
    finally:
        stop.append(True)
        for thread in threads:
            thread.join()
        errors = [thread.error for thread in threads if thread.error is not None]
        for node in nodes:
            if on_exit is not None:
                on_exit(node)
            node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown()
    if errors:
        raise errors[0]
    return 0


def _spin_in_thread(node, own, stop: list) -> threading.Thread:
    """Spin ``node`` on a new thread, ``own.niceness`` nicer than the process, until ``stop``; then make the
    calls still handed to it (``own.waiting()``; at most ``OWN_THREAD_DRAIN_S``) so that none is lost on exit.
    A SingleThreadedExecutor: the hand-over wakes it by a guard condition, which the EventsExecutor lacks."""
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)

    def spin():
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + own.niceness))
        try:
            spin_until(executor, lambda: bool(stop))
            deadline = time.monotonic() + OWN_THREAD_DRAIN_S
            spin_until(executor, lambda: not own.waiting() or time.monotonic() >= deadline, 0.1)
        except BaseException as exc:  # the process stops and raises it, as it would on its main thread
            thread.error = exc
            stop.append(True)
        finally:
            executor.remove_node(node)
            executor.shutdown()

    thread = threading.Thread(target=spin, name=f'{node.get_name()}_own_thread', daemon=True)
    thread.error = None
    thread.start()
    return thread
