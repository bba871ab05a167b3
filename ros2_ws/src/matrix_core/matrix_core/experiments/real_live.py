"""The real-data row of the experiments: the shipped default detector on the real MATRIX sample
through the live graph, the path of ``make demo``. The sample becomes a rosbag2, ``run_graph`` replays it in
lockstep through every node (calib + register per drone, fuse, recorder), and the recording is scored against
the bag's ground truth (``matrix-tracker evaluate-recording``). Only child processes touch ROS: this module
imports neither rclpy nor messages.

The sample's frames 0-4 are the real validation set on which the default checkpoint was selected
(docs/detector.md): its figures are no test accuracy, and the report says so.
"""

import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from matrix_core.fusion.settings import shipped_checkpoint

STEP = 'tables/matrix_sample_live'
DATASET = 'shared:matrix_sample'


def checkpoint_sha256(name: str) -> str:
    """sha256 of a shipped checkpoint: part of the step's cache key, so a new default model reruns the step."""
    return hashlib.sha256(shipped_checkpoint(name).read_bytes()).hexdigest()


def step_params(checkpoint: str) -> dict:
    return {'dataset': DATASET, 'checkpoint': checkpoint, 'checkpoint_sha256': checkpoint_sha256(checkpoint)}


def _run(cmd: list, out: Path, log_name: str, env: dict) -> None:
    """Run ``cmd``, its output into ``out/log_name``; a non-zero exit raises with the end of that log."""
    with open(out / log_name, 'w') as f:
        rc = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env).returncode
    if rc != 0:
        tail = (out / log_name).read_text()[-800:]
        raise RuntimeError(
            f'{" ".join(str(c) for c in cmd[:4])} ... exited with {rc}; end of {out / log_name}:\n{tail}'
        )


def run_live_real(p: dict, out: Path, run_dir: Path, progress: bool, log) -> None:
    """Step executor (``EXECUTORS['live_graph']``): writes ``out/metrics.json`` (the recording's detection,
    tracking and image-plane metrics, plus the params) and keeps the node logs in ``out/logs``."""
    from matrix_core.experiments.steps import StepUnavailable
    from matrix_core.experiments.table3 import shared_path

    root = shared_path(p['dataset'])
    if not root.is_dir():
        raise StepUnavailable(f'{root} is missing (set MATRIX_SHARED to the shared data folder)')
    if importlib.util.find_spec('matrix_bringup') is None:
        raise StepUnavailable('the ROS 2 workspace is not on the path (make setup; source scripts/env.sh)')
    checkpoint = shipped_checkpoint(p['checkpoint'])
    if checkpoint_sha256(p['checkpoint']) != p['checkpoint_sha256']:
        raise RuntimeError(f'{checkpoint} changed after the plan was made; run the experiments again')
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, 'ROS_AUTOMATIC_DISCOVERY_RANGE': os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')}
    cli = [sys.executable, '-m', 'matrix_core.cli.main']
    bag = out / 'bag'
    _run(cli + ['bag', str(root), '--out', str(bag)], out, 'bag.log', env)
    try:
        _run(
            [
                sys.executable,
                '-m',
                'matrix_bringup.run_graph',
                '--bag',
                str(bag),
                '--dataset',
                str(root),
                '--drones_per_process',
                '4',
                '--record',
                str(out / 'recording'),
                '--checkpoint',
                str(checkpoint),
                '--log_dir',
                str(out / 'logs'),
            ],
            out,
            'run_graph.log',
            env,
        )
        _run(
            cli
            + [
                'evaluate-recording',
                str(out / 'recording'),
                '--ground-truth',
                str(bag),
                '--dataset',
                str(root),
                '--json',
                str(out / 'live_metrics.json'),
            ],
            out,
            'evaluate.log',
            env,
        )
    finally:
        shutil.rmtree(bag, ignore_errors=True)  # raw 1080p images of the sample (about 250 MB), made again on demand
    live = json.loads((out / 'live_metrics.json').read_text())
    record = {
        **p,
        'path': str(root),
        'detection': live['detection'],
        'tracking': live['tracking'],
        'hota': live.get('hota'),
        'image_plane_all': live.get('image_plane', {}).get('per_drone', {}).get('all'),
        'frames_without_tracks': live.get('frames_without_tracks'),
    }
    (out / 'metrics.json').write_text(json.dumps(record, indent=2))
