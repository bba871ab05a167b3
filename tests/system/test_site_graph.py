"""System test: a site dataset and a user's own recording of it run through the live graph as they are.

A small site that is not MATRIX (three drones with names of their own, the plaza's cameras, boards and kiosk)
is simulated into a site dataset, `matrix-tracker bag` writes its sequence bag, and `run_graph` replays it with
only `--site DIR/site.yaml`: no dataset folder, each drone's references and cameras from the site file. calib
and register must publish for every drone with small errors (graph_monitor's scores against the bag's ground
truth) and fuse must publish tracks. The same frames as a camera stack records them (images and a camera
driver's camera_info, under other topic names, no ground truth) then run through `ros2 launch` with
`remap:=`, the evaluation skipped and said so; without the remapping that recording names drones the site
does not have and is refused before anything starts."""

import csv
import re
import subprocess
from pathlib import Path

import pytest
import ros_helpers
import yaml
from rosbags.rosbag2 import Reader, StoragePlugin, Writer

from matrix_core import topics
from matrix_core.bags.messages import TYPESTORE
from matrix_core.bags.salvage import topic_counts
from matrix_core.cli.main import main as cli
from matrix_core.evaluation.recording import read_recording_bag
from matrix_core.site import site_path

pytestmark = [pytest.mark.ros, pytest.mark.slow]
DRONES = ['kestrel', 'osprey', 'heron']
FRAMES = 3
CHECKPOINT = 'detector_tiny_seed0.pt'  # detection quality is not the point here; the small network is quick


def _site_file(path: Path) -> Path:
    """The plaza with three of its drones, renamed."""
    site = yaml.safe_load(site_path('plaza').read_text())
    kept = [site['drones'][i] for i in (0, 2, 3)]
    site.update(name='yard', drones=[{**d, 'name': n} for d, n in zip(kept, DRONES)])
    path.write_text(yaml.safe_dump(site, sort_keys=False))
    return path


def _own_recording(bag: Path, out: Path, rename: dict) -> Path:
    """``bag`` as a user's camera stack would record it: each drone's images (renamed ``/<drone>/...`` ->
    ``/<rename[drone]>/...``) and a camera_info beside them (here the ground truth's, as a driver publishes
    its own), nothing else: no ground truth, no stored sequence clock."""
    with Reader(bag) as reader, Writer(out, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        kept = {}
        for c in reader.connections:
            drone, _, stream = c.topic.strip('/').partition('/')
            if drone in rename and stream in (topics.IMAGE_RAW, topics.IMAGE_COMPRESSED):
                kept[c.id] = writer.add_connection(f'/{rename[drone]}/{stream}', c.msgtype, typestore=TYPESTORE)
            elif drone in rename and stream == topics.GROUND_TRUTH_CAMERA_INFO:
                name = f'/{rename[drone]}/{topics.CAMERA_INFO}'
                kept[c.id] = writer.add_connection(name, c.msgtype, typestore=TYPESTORE)
        for c, time_ns, raw in reader.messages([c for c in reader.connections if c.id in kept]):
            writer.write(kept[c.id], time_ns, raw)
    return out


def _run_graph(node_executable, tmp_path: Path, name: str, *args: str) -> tuple:
    logs = tmp_path / f'{name}_logs'
    cmd = [str(node_executable('matrix_bringup', 'run_graph')), '--log_dir', str(logs), *args]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    node_logs = {p.name: p.read_text() for p in logs.glob('*.log')}
    return run, run.stdout + run.stderr + '\n'.join(f'== {k}\n{v[-3000:]}' for k, v in node_logs.items())


def test_a_site_dataset_and_a_users_recording_run_through_the_graph(node_executable, tmp_path):
    site = _site_file(tmp_path / 'yard.yaml')
    data, bag = tmp_path / 'yard', tmp_path / 'yard_bag'
    assert (
        cli(['simulate', '--site', str(site), '--frames', str(FRAMES), '--config', 'simple', '--out', str(data)]) == 0
    )
    assert cli(['bag', str(data), '--out', str(bag)]) == 0
    on_site = ['--site', str(data / 'site.yaml'), '--checkpoint', CHECKPOINT, '--lockstep_timeout', '150']

    monitor, rec = tmp_path / 'monitor', tmp_path / 'rec'
    run, said = _run_graph(
        node_executable,
        tmp_path,
        'sequence',
        '--bag',
        str(bag),
        *on_site,
        '--monitor',
        '--monitor_out',
        str(monitor),
        '--record',
        str(rec),
    )
    assert run.returncode == 0, said
    assert 'evaluation skipped' not in run.stdout
    with open(monitor / 'graph_scores.csv') as f:
        scores = list(csv.DictReader(f))
    for drone in DRONES:  # every frame of every drone calibrated and registered, close to the truth
        rows = [r for r in scores if r['view'] == drone]
        assert len(rows) == FRAMES, said
        assert all(r['rot_err_deg'] and float(r['rot_err_deg']) < 0.5 for r in rows), rows
        assert all(r['centre_err_m'] and float(r['centre_err_m']) < 0.3 for r in rows), rows
        assert all(r['reg_ground_err_m'] and float(r['reg_ground_err_m']) < 0.5 for r in rows), rows
    recording = read_recording_bag(rec)
    assert len(set(recording.track_frames)) == FRAMES  # a TrackArray for every frame
    assert recording.tracks is not None and len(recording.tracks.frames) > 0  # and tracks in it

    # The same frames as the user's camera stack records them: other topic names, no ground truth.
    rename = {d: f'cam_{k}' for k, d in enumerate(DRONES)}
    own = _own_recording(bag, tmp_path / 'own_bag', rename)
    refused, said = _run_graph(node_executable, tmp_path, 'refused', '--bag', str(own), *on_site)
    assert refused.returncode == 2, said
    assert 'names drones cam_0, cam_1, cam_2, which site yard' in refused.stderr
    assert not (tmp_path / 'refused_logs').exists()  # refused before any process started

    # every topic that names a drone is remapped, its camera_info too (the player then leaves that one out)
    streams = (topics.IMAGE_RAW, topics.CAMERA_INFO)
    remap = [f'/{n}/{stream}:=/{d}/{stream}' for d, n in rename.items() for stream in streams]
    rec2 = tmp_path / 'rec_own'
    launched = ros_helpers.ros2(  # this one through `ros2 launch`: the same graph, its arguments as launch's
        'launch',
        'matrix_bringup',
        'full_graph.launch.py',
        f'bag:={own}',
        f'site:={data / "site.yaml"}',
        f'checkpoint:={CHECKPOINT}',
        'lockstep_timeout:=150',
        f'remap:=[{",".join(remap)}]',
        'monitor:=true',
        f'record:={rec2}',
        timeout_s=600,
    )
    assert launched.returncode == 0, launched.stdout[-6000:]
    assert 'full_graph: evaluation skipped' in launched.stdout, launched.stdout[-6000:]
    assert not re.search(r'\[graph_monitor-\d+\]', launched.stdout)  # the graph ran without it
    own_tracks = read_recording_bag(rec2)
    assert len(set(own_tracks.track_frames)) == FRAMES
    # the driver's camera_info was not replayed onto calib's output topic: the recording holds calib's only
    recorded = topic_counts(rec2)[0]
    assert all(recorded[topics.absolute(d, topics.CAMERA_INFO)][1] == FRAMES for d in DRONES), recorded
    evaluated = subprocess.run(
        ['matrix-tracker', 'evaluate-recording', str(rec2), '--ground-truth', str(own)], capture_output=True, text=True
    )
    assert evaluated.returncode == 0 and 'evaluation skipped' in evaluated.stdout, evaluated.stdout + evaluated.stderr
