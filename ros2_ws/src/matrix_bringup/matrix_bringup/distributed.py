"""Run a :class:`~matrix_bringup.deployment.Deployment` on :class:`~matrix_bringup.netns_harness.Hosts`: each
host's processes in its namespace, with the DDS discovery of choice, plus ``link_probe`` observers; and the
replay bag such a run plays. Used by tests/system/test_distributed.py and scripts/bench_distributed.py.

Discovery (``DISCOVERY``): ``multicast``: Fast DDS's default SIMPLE discovery over the links
(``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET``; the default ``LOCALHOST`` of this workspace would never leave a
host) with config/fastdds_hosts.xml; ``peers``: config/fastdds_peers.xml, unicast to a fixed list of peers, no
multicast at all (for links that do not pass it).
"""

import os
import sys
import time
from dataclasses import replace
from pathlib import Path

from matrix_bringup.deployment import GROUND, Deployment
from matrix_bringup.graph import share_file
from matrix_bringup.netns_harness import Hosts
from matrix_bringup.run_graph import executable_path

# name -> (profile under share/matrix_bringup/config, ROS_AUTOMATIC_DISCOVERY_RANGE)
DISCOVERY = {'multicast': ('fastdds_hosts.xml', 'SUBNET'), 'peers': ('fastdds_peers.xml', 'SYSTEM_DEFAULT')}


def host_env(discovery: str = 'multicast') -> dict:
    """The environment of every process of a distributed run (ROS_DOMAIN_ID as this process's)."""
    profile, scope = DISCOVERY[discovery]
    env = {k: v for k, v in os.environ.items() if k not in ('ROS_STATIC_PEERS', 'ROS_LOCALHOST_ONLY')}
    env.update({'ROS_AUTOMATIC_DISCOVERY_RANGE': scope,
                'FASTRTPS_DEFAULT_PROFILES_FILE': share_file('matrix_bringup', 'config', profile)})
    return env


def log_path(log_dir: Path, label: str) -> Path:
    return Path(log_dir) / (label.replace('/', '_') + '.log')


def start(d: Deployment, hosts: Hosts, log_dir: Path, discovery: str = 'multicast', image_probes=(),
          player_lead_s: float = 10.0, timeout_s: float = 300.0) -> dict:
    """Start a ``link_probe`` of fuse's output on the ground (label 'ground/probe'), one of the images on each
    drone of ``image_probes`` ('Dn/probe'; its player then waits for that reader too), then the deployment's
    processes in their hosts, the ground first. The players come last, once fuse has every drone's geometry
    stream connected (``timeout_s``), all with the same ``start_at``, ``player_lead_s`` from then: frame k
    leaves every drone host at the same time, as from cameras on a common clock. Returns label -> Popen;
    logs in ``log_dir/<label>.log`` (the probes': JSON lines, see matrix_bringup.link_probe)."""
    env, procs = host_env(discovery), {}

    def run(host, label, cmd):
        procs[label] = hosts.start(host, cmd, log_path(log_dir, label), env)

    probe = [sys.executable, '-m', 'matrix_bringup.link_probe']
    run(GROUND, 'ground/probe', [*probe, '--fuse'])
    for view in image_probes:
        run(view, f'{view}/probe', [*probe, '--images', view])
    players = []
    for host in [GROUND, *d.drones]:
        for spec in d.hosts[host]:
            if spec.executable == 'bag_player':
                players.append((host, spec))
            else:
                run(host, spec.label, [executable_path(spec.package, spec.executable), *spec.ros_args()])
    _wait_connected(procs, log_path(log_dir, 'fuse'), len(d.drones), timeout_s)
    start_at = time.time() + player_lead_s
    for host, spec in players:
        extra = sum(1 for v in image_probes if v == host)
        params = {**spec.parameters, 'start_at': start_at,
                  'wait_for_subscribers': spec.parameters['wait_for_subscribers'] + extra}
        spec = replace(spec, parameters=params)
        run(host, spec.label, [executable_path(spec.package, spec.executable), *spec.ros_args()])
    return procs


def restart(d: Deployment, hosts: Hosts, log_dir: Path, label: str, discovery: str = 'multicast'):
    """Start the process ``label`` of the deployment again (after it was stopped), logging to
    ``log_dir/<label>_restarted.log``."""
    host = d.host_of(label)
    spec = next(n for n in d.hosts[host] if n.label == label)
    return hosts.start(host, [executable_path(spec.package, spec.executable), *spec.ros_args()],
                       log_path(log_dir, f'{label}_restarted'), host_env(discovery))


def _wait_connected(procs: dict, fuse_log: Path, drones: int, timeout_s: float) -> None:
    """Until fuse logged that every drone's geometry stream connected (its images are then subscribed)."""
    deadline = time.monotonic() + timeout_s
    while Path(fuse_log).read_text().count('connected; images subscribed') < drones:
        dead = {label: p.returncode for label, p in procs.items() if p.poll() is not None}
        if dead or time.monotonic() > deadline:
            raise RuntimeError(f'fuse did not connect to all {drones} drones ({fuse_log}); '
                               + (f'exited: {dead}' if dead else f'after {timeout_s:g} s'))
        time.sleep(0.2)


def read_probe(log: Path) -> list:
    """The JSON lines a probe wrote so far (its first line is its command)."""
    import json
    lines = Path(log).read_text().splitlines()[1:] if Path(log).is_file() else []
    out = []
    for line in lines:
        if line.startswith('{'):
            try:
                out.append(json.loads(line))
            except ValueError:   # a line being written
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
            bag.write_frame(i, {v: ds.load_image(v, frame) for v in views},
                            {v: ds.camera(v, frame) for v in views}, ds.pedestrian_positions(frame))
    return Path(out)


def back_and_forth(n_frames: int, length: int) -> list:
    """[0, 1, ..., n-1, n-2, ..., 0, 1, ...] of ``length``: continuous motion for calib's corner tracking."""
    cycle = list(range(n_frames)) + list(range(n_frames - 2, 0, -1))
    return [cycle[i % len(cycle)] for i in range(length)]
