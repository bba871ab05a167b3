"""Drones a node cannot serve from the start because their start-up inputs cannot be read (the reference
image or calibration: ``matrix_core.datasets.drone_inputs``): the node serves the others, logs each one left
out once, and says so on ``/diagnostics``; a node left with no drone cannot start.

Their statuses are named ``<node>/<view>/start_up`` (hardware id: the view), apart from the per-frame
``<node>/<view>`` that ``graph_monitor`` counts as a processed frame.
"""

from rclpy.clock import Clock, ClockType

from matrix_core.datasets.drone_inputs import left_out_text
from matrix_ros import diagnostics

REPORT_PERIOD_S = 1.0  # as diagnostic_updater publishes: a monitor started later still learns of them


class NoDroneCanStart(ValueError):
    """Every drone of a node was left out: the node cannot start (one line naming them, exit code 2)."""


def start_up_statuses(node_name: str, problems: dict, level, what: str) -> list:
    """One DiagnosticStatus ``<node_name>/<view>/start_up`` per view of ``problems`` (view -> why), its
    message ``'<what>: <why>'``."""
    return [
        diagnostics.status(f'{node_name}/{view}/start_up', level, f'{what}: {why}', {'reason': why}, view)
        for view, why in sorted(problems.items())
    ]


def served_drones(node, hosted: list, left_out: dict) -> list:
    """The ``hosted`` (view, prefix) pairs not in ``left_out`` (view -> why); each one left out logged once as
    an error. :class:`NoDroneCanStart` naming them when none is left."""
    served = [(view, prefix) for view, prefix in hosted if view not in left_out]
    if left_out and not served:
        raise NoDroneCanStart(f'{node.get_name()}: no drone can start: {left_out_text(left_out)}')
    for view, why in sorted(left_out.items()):
        node.get_logger().error(f'{view}: left out at start ({why}); serving {", ".join(v for v, _ in served)}')
    return served


class LeftOutReport:
    """The drones ``node`` left out at start on ``/diagnostics`` (``publisher``, the node's): their
    ``start_up`` statuses at ERROR now and every ``period_s`` on the steady clock (sim time stands still
    while a lockstep player waits); nothing when none was left out."""

    def __init__(self, node, left_out: dict, publisher, period_s: float = REPORT_PERIOD_S):
        self.node, self.left_out, self.pub = node, dict(left_out), publisher
        if not self.left_out:
            return
        self.statuses = start_up_statuses(node.get_name(), self.left_out, diagnostics.ERROR, 'left out')
        self.publish()
        node.create_timer(period_s, self.publish, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def publish(self) -> None:
        self.pub.publish(diagnostics.array(self.node.get_clock().now().to_msg(), *self.statuses))
