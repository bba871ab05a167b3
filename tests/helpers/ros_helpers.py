"""What the DDS tests do again and again: start an installed node in its own process, spin a test node until
something arrived or an endpoint matched, and stop the processes collecting their output.

Importable as ``ros_helpers`` from tests/ and ros2_ws/src/*/test/ alike: the root conftest.py puts this folder
on ``sys.path`` (pytest runs with ``--import-mode=importlib``, so test folders are no packages).

Wait for endpoints or messages, never for a fixed time: on a loaded machine discovery takes from milliseconds
to seconds. A publisher's ``get_subscription_count()`` and a subscription's ``get_publisher_count()`` count
the DDS endpoints that matched this side; ``count_publishers``/``count_subscribers`` only say an endpoint
exists somewhere in the graph.
"""

import os
import signal
import subprocess
import time
from typing import Callable, Iterable

import rclpy


def start_node(executable, *params: str, env: dict = None) -> subprocess.Popen:
    """Run an installed node (``node_executable(package, name)``) with ``-p`` parameters ('name:=value');
    its stdout and stderr are collected as text (read them with :func:`stop` or :func:`finish`)."""
    args = [str(executable), '--ros-args', *[a for p in params for a in ('-p', p)]]
    return subprocess.Popen(
        args,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=None if env is None else {**os.environ, **env},
    )


def ros2(*args: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess:
    """Run the ``ros2`` command line to completion (``scripts/env.sh`` puts it on PATH: a ROS install's, or
    the one scripts/build_cli.sh built); stdout and stderr together as text in ``.stdout``."""
    return subprocess.run(
        ['ros2', *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout_s
    )


def ros2_graph(verb: str, *args: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess:
    """``ros2 VERB SUBVERB ARGS...`` for the verbs that look at the graph (node, param, topic, service), with
    no ros2 daemon (a test leaves none behind). Without the daemon the CLI discovers the graph itself within
    ``--spin-time`` seconds, all of which it waits: tried with 2 s, and again with longer on a loaded
    machine while it prints nothing or says a node was not found."""
    for spin_s in (2, 5, 15):
        run = ros2(verb, *args[:1], '--no-daemon', '--spin-time', str(spin_s), *args[1:], timeout_s=timeout_s)
        if run.stdout.strip() and 'not found' not in run.stdout.lower():
            break
    return run


def start_ros2(*args: str) -> subprocess.Popen:
    """Start ``ros2 ARGS...`` (``ros2 run``, ``ros2 launch``, ``ros2 topic echo``) in its own process group,
    so that :func:`stop` reaches everything it started; output collected as text."""
    return subprocess.Popen(
        ['ros2', *args], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True
    )


def finish(process: subprocess.Popen, timeout_s: float = 20.0, why: str = 'did not exit') -> str:
    """Output of ``process`` once it exited; killed (no orphans) if it has not exited within ``timeout_s``,
    the output then ending in ``[killed: WHY]``."""
    try:
        return process.communicate(timeout=timeout_s)[0] or ''  # '' when not piped
    except subprocess.TimeoutExpired:
        _kill(process)
        return (process.communicate()[0] or '') + f'\n[killed: {why}]'


def _kill(process: subprocess.Popen) -> None:
    """SIGKILL to the process, and to its group if it leads one (:func:`start_ros2`: ``ros2 run`` leaves its
    node running when it is killed, and the node holds the output pipe open)."""
    try:
        if os.getpgid(process.pid) == process.pid:
            os.killpg(process.pid, signal.SIGKILL)
            return
    except ProcessLookupError:
        return
    process.kill()


def stop(process: subprocess.Popen, timeout_s: float = 20.0) -> str:
    """SIGTERM (if still running), then :func:`finish`: the process's whole output."""
    if process.poll() is None:
        process.terminate()
    return finish(process, timeout_s)


def interrupt(process: subprocess.Popen, timeout_s: float = 30.0) -> str:
    """Ctrl-C as in a terminal, for a process of :func:`start_ros2`: SIGINT to its whole process group (``ros2
    run`` does not pass SIGTERM on to the node it started); the group is killed if it has not exited within
    ``timeout_s``. Returns the output."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGINT)
    return finish(process, timeout_s, 'did not exit on SIGINT')


def interrupt_all(processes: Iterable[subprocess.Popen], timeout_s: float = 30.0) -> list:
    """:func:`interrupt` for every process of :func:`start_ros2`: SIGINT to all first (they shut down
    together), then each one's output, in order."""
    processes = list(processes)
    for p in processes:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGINT)
    # one SIGINT each: a second one while `ros2 launch` shuts down makes it abort with a KeyboardInterrupt
    # traceback (seen when a node took long to exit on a loaded machine)
    return [finish(p, timeout_s, 'did not exit on SIGINT') for p in processes]


def stop_all(processes: Iterable[subprocess.Popen], timeout_s: float = 20.0) -> list:
    """SIGTERM to every process first (they shut down together), then each one's output, in order."""
    processes = list(processes)
    for p in processes:
        if p.poll() is None:
            p.terminate()
    return [finish(p, timeout_s) for p in processes]


def spin_until(
    node, done: Callable[[], bool], processes: Iterable[subprocess.Popen] = (), timeout_s: float = 30.0, executor=None
) -> bool:
    """Spin ``node`` (or ``executor``, which holds it) until ``done()``, the timeout, or one of ``processes``
    exited; returns ``done()``."""
    processes = list(processes)
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and not done() and all(p.poll() is None for p in processes):
        if executor is not None:
            executor.spin_once(timeout_sec=0.05)
        else:
            rclpy.spin_once(node, timeout_sec=0.05)
    return done()


def spin_for(node, seconds: float, executor=None) -> None:
    """Spin for a fixed time: only where the time itself is what a test exercises (say why at the call)."""
    spin_until(node, lambda: False, timeout_s=seconds, executor=executor)


def wait_matched(
    node,
    endpoints: Iterable,
    processes: Iterable[subprocess.Popen] = (),
    timeout_s: float = 60.0,
    count: int = 1,
    executor=None,
) -> None:
    """Spin until every publisher has at least ``count`` matched subscriptions and every subscription at least
    ``count`` matched publishers (``count=0``: none, the other side is gone); fails naming those still waiting."""
    endpoints, processes = list(endpoints), list(processes)

    def matched(e) -> int:
        return e.get_subscription_count() if hasattr(e, 'get_subscription_count') else e.get_publisher_count()

    def ok(e) -> bool:
        return matched(e) >= count if count else matched(e) == 0

    if not spin_until(node, lambda: all(map(ok, endpoints)), processes, timeout_s, executor):
        waiting = [f'{e.topic_name} ({matched(e)})' for e in endpoints if not ok(e)]
        exited = [p.args[0] for p in processes if p.poll() is not None]
        raise AssertionError(
            f'not matched ({count} each): {", ".join(waiting)}; '
            + (f'exited: {exited}' if exited else f'waited {timeout_s:g} s')
        )


def wait_for(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll ``condition`` (no ROS node: e.g. a file another process writes) until true; fails saying ``what``."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f'after {timeout_s:g} s still waiting for {what}')
        time.sleep(0.05)
