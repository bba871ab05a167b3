"""The executor every node process of the graph spins: rclpy's EventsExecutor unless the environment says
otherwise.

rclpy's SingleThreadedExecutor rebuilds its wait set over all of a node's entities for every callback: a node
with many subscriptions and cheap callbacks pays more for the executor than for its work (the recorder, 34
topics of the 8 drones: 0.04 CPU s per frame, 0.01 with the EventsExecutor, scripts/bench_graph.py simulated
lockstep). The EventsExecutor is rclpy's own (``rclpy.experimental``, Jazzy): ``MATRIX_ROS_EXECUTOR=single``
selects the SingleThreadedExecutor for a process should it misbehave.
"""

import os

import rclpy.executors
from rclpy.experimental import EventsExecutor

EXECUTOR_VARIABLE = 'MATRIX_ROS_EXECUTOR'
EXECUTORS = {'events': EventsExecutor, 'single': rclpy.executors.SingleThreadedExecutor}


def make_executor():
    """A new executor of the kind ``$MATRIX_ROS_EXECUTOR`` names (``events``, the default, or ``single``) in
    the default context (call after ``rclpy.init``)."""
    name = os.environ.get(EXECUTOR_VARIABLE, '') or 'events'
    if name not in EXECUTORS:
        raise ValueError(f'{EXECUTOR_VARIABLE}={name!r}: choose one of {sorted(EXECUTORS)}')
    return EXECUTORS[name]()
