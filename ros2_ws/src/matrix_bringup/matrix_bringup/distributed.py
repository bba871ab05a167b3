"""Run a :class:`~matrix_bringup.deployment.Deployment` on :class:`~matrix_bringup.netns_harness.Hosts`: each
host's processes in its namespace, with the DDS discovery of choice, plus ``link_probe`` observers; and the
replay bag such a run plays. Used by tests/system/test_distributed.py and scripts/bench_distributed.py.

Discovery (``DISCOVERY``): ``multicast``: Fast DDS's default SIMPLE discovery over the links
(``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET``; the default ``LOCALHOST`` of this workspace would never leave a
host) with config/fastdds_hosts.xml; ``peers``: config/fastdds_peers.xml, unicast to a fixed list of peers, no
multicast at all (for links that do not pass it); ``server``: a discovery server on the ground
(``matrix_bringup.discovery_server``, started first) and every other process its client by
config/fastdds_client.xml, no multicast either; ``server_env``: the same server, the clients made by Fast DDS
from ``ROS_DISCOVERY_SERVER`` with config/fastdds_hosts.xml (the other way to set it up).
"""

import os
import sys
import time
from dataclasses import replace
from pathlib import Path

from matrix_bringup.deployment import GROUND, Deployment
from matrix_bringup.graph import share_file
from matrix_bringup.netns_harness import Hosts, address
from matrix_bringup.run_graph import command
from matrix_core import topics

SERVER_PORT = 11811  # of the discovery server (config/fastdds_server.xml, fastdds_client.xml)
# name -> (profile under share/matrix_bringup/config, ROS_AUTOMATIC_DISCOVERY_RANGE, other variables)
DISCOVERY = {
    'multicast': ('fastdds_hosts.xml', 'SUBNET', {}),
    'peers': ('fastdds_peers.xml', 'SYSTEM_DEFAULT', {}),
    'server': ('fastdds_client.xml', 'SYSTEM_DEFAULT', {}),
    'server_env': ('fastdds_hosts.xml', 'SYSTEM_DEFAULT', {'ROS_DISCOVERY_SERVER': f'{address(GROUND)}:{SERVER_PORT}'}),
}
SERVED = ('server', 'server_env')  # discovery modes that need matrix_bringup.discovery_server on the ground


def host_env(discovery: str = 'multicast') -> dict:
    """The environment of every process of a distributed run (ROS_DOMAIN_ID as this process's)."""
    profile, scope, extra = DISCOVERY[discovery]
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ('ROS_STATIC_PEERS', 'ROS_LOCALHOST_ONLY', 'ROS_DISCOVERY_SERVER')
    }
    env.update(
        {
            'ROS_AUTOMATIC_DISCOVERY_RANGE': scope,
            'FASTRTPS_DEFAULT_PROFILES_FILE': share_file('matrix_bringup', 'config', profile),
            **extra,
        }
    )
    return env


def log_path(log_dir: Path, label: str) -> Path:
    return Path(log_dir) / (label.replace('/', '_') + '.log')


def start(
    d: Deployment,
    hosts: Hosts,
    log_dir: Path,
    discovery: str = 'multicast',
    image_probes=(),
    captures=(),
    player_lead_s: float = 5.0,
    timeout_s: float = 300.0,
) -> dict:
    """Start the discovery server on the ground if ``discovery`` needs one ('ground/discovery_server'), a
    ``link_probe`` of fuse's output on the ground (label 'ground/probe'), one of the images on each
    drone of ``image_probes`` ('Dn/probe'; its player then waits for that reader too), a ``link_capture`` of
    the link of each drone of ``captures`` ('Dn/capture', before any DDS traffic), then the deployment's
    processes in their hosts, the ground first. Once fuse has every drone's geometry stream connected
    (``timeout_s``), ``matrix_bringup.start_signal`` ('ground/start_signal') waits for every player to be ready
    and gives them all the same start time, ``player_lead_s`` later: frame k leaves every drone host at the
    same time, as from cameras on a common clock; returns then (frame 0 leaves ``player_lead_s`` later) the
    processes by label -> Popen;
    logs in ``log_dir/<label>.log`` (the probes': JSON lines, see matrix_bringup.link_probe)."""
    env, procs = host_env(discovery), {}

    def run(host, label, cmd):
        procs[label] = hosts.start(host, cmd, log_path(log_dir, label), env)

    for view in captures:
        names = [f'{h}={hosts.address(h)}' for h in hosts.hosts]
        run(view, f'{view}/capture', [sys.executable, '-m', 'matrix_bringup.link_capture', '--hosts', *names])
    _wait(
        lambda: all(read_probe(log_path(log_dir, f'{v}/capture')) for v in captures),
        procs,
        60.0,
        'the link captures to start',
    )
    if discovery in SERVED:  # before its clients: they announce themselves to it only
        run(GROUND, 'ground/discovery_server', [sys.executable, '-m', 'matrix_bringup.discovery_server'])
    probe = [sys.executable, '-m', 'matrix_bringup.link_probe']
    run(GROUND, 'ground/probe', [*probe, '--fuse'])
    for view in image_probes:
        run(view, f'{view}/probe', [*probe, '--images', view])
    players = 0
    for host in [GROUND, *d.drones]:
        for spec in d.hosts[host]:
            if spec.executable == 'bag_player':
                players += 1
                extra = sum(1 for v in image_probes if v == host)
                params = {
                    **spec.parameters,
                    'start_topic': topics.PLAYER_START_TOPIC,
                    'wait_for_subscribers': spec.parameters['wait_for_subscribers'] + extra,
                }
                spec = replace(spec, parameters=params)
            run(host, spec.label, command(spec))
    _wait_connected(procs, log_path(log_dir, 'fuse'), len(d.drones), timeout_s)
    signal = [
        sys.executable,
        '-m',
        'matrix_bringup.start_signal',
        '--players',
        str(players),
        '--lead',
        str(player_lead_s),
    ]
    run(GROUND, 'ground/start_signal', signal)
    started = log_path(log_dir, 'ground/start_signal')
    _wait(lambda: 'players ready' in started.read_text(), procs, timeout_s, f'every player to be ready ({started})')
    return procs


def restart(d: Deployment, hosts: Hosts, log_dir: Path, label: str, discovery: str = 'multicast'):
    """Start the process ``label`` of the deployment again (after it was stopped), logging to
    ``log_dir/<label>_restarted.log``."""
    host = d.host_of(label)
    spec = next(n for n in d.hosts[host] if n.label == label)
    return hosts.start(host, command(spec), log_path(log_dir, f'{label}_restarted'), host_env(discovery))


def _wait_connected(procs: dict, fuse_log: Path, drones: int, timeout_s: float) -> None:
    """Until fuse logged that every drone's geometry stream connected (its images are then subscribed)."""
    _wait(
        lambda: Path(fuse_log).read_text().count('connected; images subscribed') >= drones,
        procs,
        timeout_s,
        f'fuse to connect to all {drones} drones ({fuse_log})',
    )


def _wait(condition, procs: dict, timeout_s: float, what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        dead = {label: p.returncode for label, p in procs.items() if p.poll() is not None}
        if dead or time.monotonic() > deadline:
            raise RuntimeError(f'waited for {what}: ' + (f'exited: {dead}' if dead else f'not after {timeout_s:g} s'))
        time.sleep(0.2)


def read_probe(log: Path) -> list:
    """The JSON lines a probe or a capture wrote so far (its first line is its command)."""
    import json

    lines = Path(log).read_text().splitlines()[1:] if Path(log).is_file() else []
    out = []
    for line in lines:
        if line.startswith('{'):
            try:
                out.append(json.loads(line))
            except ValueError:  # a line being written
                pass
    return out


def write_replay_bag(dataset_dir, out, views, frames) -> Path:
    """A compressed sequence bag of ``views`` playing the dataset's frames at the indices ``frames`` in that
    order (e.g. back and forth over the real sample's 5 frames for a longer replay), stamps going on at the
    sequence clock's period."""
    from matrix_core.bags.writer import SequenceBagWriter
    from matrix_core.datasets import open_dataset

    ds = open_dataset(dataset_dir)
    with SequenceBagWriter(out, views, compressed=True) as bag:
        for i, k in enumerate(frames):
            frame = ds.frames[k]
            bag.write_frame(
                i,
                {v: ds.load_image(v, frame) for v in views},
                {v: ds.camera(v, frame) for v in views},
                ds.pedestrian_positions(frame),
            )
    return Path(out)


def back_and_forth(n_frames: int, length: int) -> list:
    """[0, 1, ..., n-1, n-2, ..., 0, 1, ...] of ``length``: continuous motion for calib's corner tracking."""
    cycle = list(range(n_frames)) + list(range(n_frames - 2, 0, -1))
    return [cycle[i % len(cycle)] for i in range(length)]
