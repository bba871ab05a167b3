"""The executor every node process of the graph spins: rclpy's EventsExecutor unless the environment says
otherwise.

rclpy's SingleThreadedExecutor rebuilds its wait set over all of a node's entities for every callback: a node
with many subscriptions and cheap callbacks pays more for the executor than for its work (the recorder, 34
topics of the 8 drones: 0.04 CPU s per frame, 0.01 with the EventsExecutor, scripts/bench_graph.py simulated
lockstep). The EventsExecutor is rclpy's own (``rclpy.experimental``, Jazzy): ``MATRIX_ROS_EXECUTOR=single``
selects the SingleThreadedExecutor for a process should it misbehave.

Every node process spins with :func:`spin_until`: ``executor.spin()`` of the EventsExecutor does not return
when SIGINT or SIGTERM shut the context down (rclpy's own signal handlers; Jazzy, measured: it blocks until
killed), ``spin_once`` with a timeout does, so the process stops cleanly either way.
"""

import os

import rclpy
import rclpy.executors
from rclpy.executors import ExternalShutdownException
from rclpy.experimental import EventsExecutor

EXECUTOR_VARIABLE = 'MATRIX_ROS_EXECUTOR'
SPIN_SLICE_S = 0.5  # longest wait for work before ``done`` is checked (0.1 s cost an idle node 0.7 % of a core)
EXECUTORS = {'events': EventsExecutor, 'single': rclpy.executors.SingleThreadedExecutor}


def make_executor():
    """A new executor of the kind ``$MATRIX_ROS_EXECUTOR`` names (``events``, the default, or ``single``) in
    the default context (call after ``rclpy.init``)."""
    name = os.environ.get(EXECUTOR_VARIABLE, '') or 'events'
    if name not in EXECUTORS:
        raise ValueError(f'{EXECUTOR_VARIABLE}={name!r}: choose one of {sorted(EXECUTORS)}')
    return EXECUTORS[name]()


def spin_until(executor, done=lambda: False, slice_s: float = SPIN_SLICE_S) -> None:
    """Spin ``executor`` until ``done()`` or until the context is shut down (a signal through rclpy's handlers,
    ``rclpy.shutdown``: then it returns quietly), waiting at most ``slice_s`` for work between checks.

    A shutdown that lands inside ``spin_once`` surfaces as ExternalShutdownException or, when it comes while
    the wait set is being made, as rclpy's RCLError "the given context is not valid": both end the spinning;
    an error while the context is still up is raised."""
    try:
        while rclpy.ok() and not done():
            executor.spin_once(timeout_sec=slice_s)
    except ExternalShutdownException:
        pass
    except Exception:
        if rclpy.ok():
            raise
