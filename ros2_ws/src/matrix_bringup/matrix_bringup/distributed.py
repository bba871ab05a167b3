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


def start(d: Deployment, hosts: Hosts, log_dir: Path, discovery: str = 'multicast', image_probes=()) -> dict:
    """Start a ``link_probe`` of fuse's output on the ground (label 'ground/probe'), one of the images on each
    drone of ``image_probes`` ('Dn/probe'; its player then waits for that reader too), then the deployment's
    processes in their hosts, the ground first and each drone's player last. Returns label -> Popen; logs
    in ``log_dir/<label>.log`` (the probes': JSON lines, see matrix_bringup.link_probe)."""
    env, procs = host_env(discovery), {}
    probe = [sys.executable, '-m', 'matrix_bringup.link_probe']
    procs['ground/probe'] = hosts.start(GROUND, [*probe, '--fuse'], log_path(log_dir, 'ground/probe'), env)
    for view in image_probes:
        procs[f'{view}/probe'] = hosts.start(view, [*probe, '--images', view], log_path(log_dir, f'{view}/probe'),
                                             env)
        d.hosts[view][-1].parameters['wait_for_subscribers'] += 1
    for host in [GROUND, *d.drones]:
        for spec in d.hosts[host]:
            cmd = [executable_path(spec.package, spec.executable), *spec.ros_args()]
            procs[spec.label] = hosts.start(host, cmd, log_path(log_dir, spec.label), env)
    return procs


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
