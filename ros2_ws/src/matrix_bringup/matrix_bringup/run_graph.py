"""``run_graph``: start the live graph of :mod:`matrix_bringup.graph` as separate processes, without ``launch``.

For environments without ``ros2 launch`` (``make setup`` builds one here; ``make demo`` uses it when it
exists): ``run_graph`` starts exactly the processes that ``full_graph.launch.py`` starts (the same
:class:`GraphSettings`, the same :func:`graph_nodes`), each found the way ``ros2 run`` finds it
(``<prefix>/lib/<package>/<executable>`` of its ament prefix) and
logging to ``LOG_DIR/<label>.log``. It waits until the player has played the whole bag (and the monitor,
if any, has written its scores), then stops every node (SIGTERM, SIGKILL after ``stop_timeout`` s); the
nodes also get SIGTERM if ``run_graph`` itself dies, so no process is left behind.

Exit code: the player's (0: every frame played and processed; 3: lockstep timed out for some frame),
4 when another node died before the end (or the monitor could score nothing), 5 when every frame was played
and processed but a drone was left out at start (its reference image or calibration cannot be read:
``drone_check``; the others run, and the exit message names it), 2 on bad settings, 130 on Ctrl-C.

    run_graph --bag BAG --dataset DIR [--record OUT/recording] [--monitor] [--drones_per_process 4] ...
    run_graph --bag BAG --site SITE.yaml [--remap /cam/image:=/alpha/image_raw ...]   (the site's references)
"""

import argparse
import ctypes
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from matrix_bringup.drone_check import LEFT_OUT_EXIT, left_out_text, ran_without_text, without_unreadable_drones
from matrix_bringup.graph import GraphSettings, NodeSpec, graph_nodes, monitor_skipped, player_exit_text
from matrix_core.settings import add_settings_arguments, settings_from_namespace

_PR_SET_PDEATHSIG = 1


def executable_path(package: str, executable: str) -> Path:
    """``<prefix of package>/lib/<package>/<executable>``, as ``ros2 run`` resolves it."""
    from ament_index_python.packages import get_package_prefix

    path = Path(get_package_prefix(package)) / 'lib' / package / executable
    if not path.is_file():
        raise FileNotFoundError(f'{path} is not built (colcon build / make build)')
    return path


def command(spec: NodeSpec) -> list:
    """The command line that starts ``spec``'s process: its prefix (``nice``), executable and ROS arguments."""
    return [*spec.prefix, str(executable_path(spec.package, spec.executable)), *spec.ros_args()]


def _die_with_parent():  # runs in the child between fork and exec
    ctypes.CDLL('libc.so.6', use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


class Graph:
    """The running processes of :class:`NodeSpec` s, each logging to its own file (``dds_profile``: the Fast DDS
    profile they all get, '' = the environment's)."""

    def __init__(self, log_dir: Path, dds_profile: str = ''):
        self.log_dir = Path(log_dir)
        self.env = {**os.environ, 'FASTRTPS_DEFAULT_PROFILES_FILE': dds_profile} if dds_profile else None
        self.procs = {}  # label -> Popen

    def start(self, spec: NodeSpec) -> None:
        self.log_dir.mkdir(parents=True, exist_ok=True)
        cmd = command(spec)
        log = open(self.log_path(spec), 'w')
        log.write(' '.join(cmd) + '\n')
        log.flush()
        self.procs[spec.label] = subprocess.Popen(
            cmd, stdout=log, stderr=subprocess.STDOUT, env=self.env, preexec_fn=_die_with_parent
        )
        log.close()

    def log_path(self, spec: NodeSpec) -> Path:
        return self.log_dir / (spec.label.replace('/', '_') + '.log')

    def cpu_seconds(self) -> dict:
        """label -> CPU seconds (user + system, all threads) each running process has used so far."""
        tick, out = os.sysconf('SC_CLK_TCK'), {}
        for label, p in self.procs.items():
            try:
                fields = Path(f'/proc/{p.pid}/stat').read_text().rsplit(')', 1)[1].split()
            except OSError:  # exited
                continue
            out[label] = (int(fields[11]) + int(fields[12])) / tick  # utime, stime
        return out

    def died(self, exclude=()) -> list:
        """Labels of processes that have exited (other than ``exclude``)."""
        return [label for label, p in self.procs.items() if label not in exclude and p.poll() is not None]

    def stop(self, timeout: float = 10.0) -> None:
        for p in self.procs.values():
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + timeout
        for p in self.procs.values():
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def run(settings: GraphSettings, log_dir: Path, stop_timeout: float = 10.0, echo=print) -> int:
    """Start the graph, play the bag, stop everything; returns the exit code described above."""
    settings, left_out = without_unreadable_drones(settings)
    if left_out:
        echo(f'run_graph: {left_out_text(left_out)}; the other drones run')
    if skipped := monitor_skipped(settings):
        echo(f'run_graph: {skipped}')
    specs = graph_nodes(settings)
    graph = Graph(log_dir, settings.dds_profile)
    player, monitor = specs[-1].label, next((s.label for s in specs if s.executable == 'graph_monitor'), None)
    interrupted = []
    previous = {sig: signal.signal(sig, lambda *_: interrupted.append(True)) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        for spec in specs:
            graph.start(spec)
        echo(f'run_graph: {len(specs)} processes ({", ".join(s.label for s in specs)}); logs in {log_dir}/')
        crashed = []
        while not interrupted and graph.procs[player].poll() is None:
            crashed = graph.died(exclude=(player,))
            if crashed:
                break
            time.sleep(0.2)
        if monitor and not crashed and not interrupted:  # the monitor settles, prints and writes its scores
            deadline = time.monotonic() + settings.lockstep_timeout
            while not interrupted and graph.procs[monitor].poll() is None and time.monotonic() < deadline:
                time.sleep(0.2)
        else:
            time.sleep(1.0)  # the recorder gets the last frame's messages
        crashed = crashed or graph.died(exclude=(player, monitor))
        if monitor and graph.procs[monitor].poll() not in (None, 0):
            crashed.append(monitor)  # it exits 1 when it could score nothing
    finally:
        graph.stop(stop_timeout)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if interrupted:
        echo('run_graph: interrupted; every node stopped')
        return 130
    if crashed:
        for label in crashed:
            spec = next(s for s in specs if s.label == label)
            echo(
                f'run_graph: {label} exited early (code {graph.procs[label].returncode}); '
                f'last lines of {graph.log_path(spec)}:'
            )
            echo(''.join(graph.log_path(spec).read_text().splitlines(keepends=True)[-15:]))
        return 4
    code = graph.procs[player].returncode
    echo(f'run_graph: player exited with {code}{player_exit_text(code)}')
    if left_out:
        echo(f'run_graph: {ran_without_text(left_out)}')
        return LEFT_OUT_EXIT if code == 0 else code
    return code


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_settings_arguments(parser, GraphSettings)
    parser.add_argument('--log_dir', default='out/graph/logs', help='one log file per node (default: out/graph/logs)')
    parser.add_argument(
        '--stop_timeout',
        type=float,
        default=10.0,
        help='seconds between SIGTERM and SIGKILL when stopping the nodes (default: 10)',
    )
    args = parser.parse_args(argv)
    try:
        settings = settings_from_namespace(GraphSettings, args)
        return run(settings, Path(args.log_dir), args.stop_timeout)
    except (ValueError, OSError) as exc:  # bad settings or input files: one line, no traceback
        print(f'run_graph: error: {exc}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    raise SystemExit(main())
