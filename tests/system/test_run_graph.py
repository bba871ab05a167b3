"""System test: `run_graph` replays a bag of the real MATRIX sample in lockstep through the whole graph
(one drone process - calib + register - per drone, fuse, recorder, graph monitor: separate processes over DDS),
exactly as `full_graph.launch.py` would start it. What the graph published is scored: the monitor's
calibration/registration errors, and the recording's tracks against the bag's ground truth. Every frame
must reach every stage, and no process may outlive the run."""

import csv
import json
import os
import subprocess

import pytest

from matrix_core.bags import write_sequence_bag
from matrix_core.cli.main import main as cli
from matrix_core.datasets import MatrixDataset
from matrix_core.evaluation.recording import read_recording_bag

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ['D1', 'D5']


def test_whole_graph_on_the_real_sample(matrix_sample, node_executable, tmp_path):
    bag = write_sequence_bag(MatrixDataset(matrix_sample), tmp_path / 'bag', compressed=True, progress=False)
    out, logs, rec = tmp_path / 'monitor', tmp_path / 'logs', tmp_path / 'rec'
    cmd = [
        str(node_executable('matrix_bringup', 'run_graph')),
        '--bag',
        str(bag),
        '--dataset',
        str(matrix_sample),
        '--views',
        *VIEWS,
        '--monitor',
        '--monitor_out',
        str(out),
        '--record',
        str(rec),
        '--log_dir',
        str(logs),
        '--lockstep_timeout',
        '150',
    ]  # the 1080p board search is slow on 2 loaded cores
    before = set(_node_processes())
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    node_logs = {p.name: p.read_text() for p in logs.glob('*.log')}
    assert run.returncode == 0, (
        run.stdout + run.stderr + '\n'.join(f'== {k}\n{v[-3000:]}' for k, v in node_logs.items())
    )
    assert sorted(node_logs) == sorted(
        [
            'D1_drone.log',
            'D5_drone.log',  # each drone's calib + register
            'fuse.log',
            'recorder.log',
            'graph_monitor.log',
            'bag_player.log',
        ]
    )
    assert 'played 5 frames' in node_logs['bag_player.log'] and 'lockstep: only' not in node_logs['bag_player.log']
    # each log starts with its command: the drone processes niced (GraphSettings.drone_niceness), fuse not
    assert node_logs['D1_drone.log'].startswith('nice -n 10 ') and node_logs['fuse.log'].startswith('/')
    assert not any('Traceback' in text for text in node_logs.values())
    leftovers = {pid: cmd for pid, cmd in _node_processes().items() if pid not in before}
    assert not leftovers, leftovers

    # calibration and registration, scored live by the monitor
    rows = list(csv.DictReader(open(out / 'graph_scores.csv')))
    assert sorted((r['view'], float(r['stamp'])) for r in rows) == sorted(
        (v, 1.0 + 0.5 * i) for v in VIEWS for i in range(5)
    )
    assert all(r['reg_status'] == 'ok' for r in rows), rows
    assert max(float(r['reg_ground_err_m']) for r in rows) < 0.1
    calibrated = [r for r in rows if r['rot_err_deg']]  # frames without a pose are reported, never wrong
    assert len(calibrated) >= 7
    assert max(float(r['rot_err_deg']) for r in calibrated) < 0.5
    assert max(float(r['centre_err_m']) for r in calibrated) < 0.3
    summary = [line.split() for line in (out / 'graph_summary.txt').read_text().splitlines()]
    assert ['all', '10'] in [row[:2] for row in summary]  # view-frames scored, as printed

    # fusion and tracking: a TrackArray for every frame, recorded with what calib and register published
    recording = read_recording_bag(rec)
    assert recording.track_frames == list(range(5))
    from rosbags.rosbag2 import Reader

    with Reader(rec) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
    assert counts['/D1/homography'] == counts['/D5/homography'] == 5 and counts['/tracks'] == 5
    # calib followed each drone's registration: every image guided by it, no board search
    assert sorted(_calib_guides(rec)) == sorted(
        (v, 1.0 + 0.5 * i, 'registration', 'True') for v in VIEWS for i in range(5)
    )
    scores = tmp_path / 'live.json'
    assert cli(['evaluate-recording', str(rec), '--ground-truth', str(bag), '--json', str(scores)]) == 0
    live = json.loads(scores.read_text())
    assert live['frames_without_tracks'] == [] and live['detections_source'] == 'detections'
    assert live['detection']['recall'] > 0.2  # two real views, the shipped checkpoint: people are found


def test_bad_settings_fail_clearly(node_executable, tmp_path):
    run = subprocess.run(
        [
            str(node_executable('matrix_bringup', 'run_graph')),
            '--bag',
            str(tmp_path / 'none'),
            '--dataset',
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2 and 'not a rosbag2 folder' in run.stderr, run.stderr


def _calib_guides(recording) -> list:
    """(view, stamp, guide, tracked) of every calib status on the recorded /diagnostics."""
    from rosbags.highlevel import AnyReader

    found = []
    with AnyReader([recording]) as reader:
        for conn, _, raw in reader.messages([c for c in reader.connections if c.topic == '/diagnostics']):
            msg = reader.deserialize(raw, conn.msgtype)
            for status in msg.status:
                if status.name.startswith('calib/'):
                    values = {kv.key: kv.value for kv in status.values}
                    stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
                    found.append((status.hardware_id, round(stamp, 3), values.get('guide'), values.get('tracked')))
    return found


def _node_processes() -> dict:
    """pid -> command line of every running process started from the colcon install."""
    found = {}
    for pid in filter(str.isdigit, os.listdir('/proc')):
        try:
            cmd = open(f'/proc/{pid}/cmdline', 'rb').read().replace(b'\0', b' ').decode(errors='replace')
        except OSError:
            continue
        if 'ros2_ws/install' in cmd and 'run_graph' not in cmd:
            found[int(pid)] = cmd
    return found


def test_whole_graph_equals_offline_on_a_simulated_sequence(node_executable, tmp_path):
    """Simulated 1920x1080 sequence through calib + register + fuse live, against the offline
    `register` + `evaluate --calibration registration` of the same checkpoint: MODA/MOTA within 1 point
    (the bag carries a JPEG of each render, the folder a JPEG of its mirrored file form: pixel noise only)."""
    from matrix_core.fusion.settings import shipped_checkpoint

    sim, rec = tmp_path / 'sim', tmp_path / 'rec'
    frames = 8
    assert (
        cli(
            [
                'simulate',
                '--config',
                'complex',
                '--frames',
                str(frames),
                '--seed',
                '5',
                '--image_ext',
                '.jpg',
                '--bag',
                '--compressed',
                '--out',
                str(sim),
            ]
        )
        == 0
    )
    checkpoint = str(shipped_checkpoint())
    run = subprocess.run(
        [
            str(node_executable('matrix_bringup', 'run_graph')),
            '--bag',
            str(sim / 'bag'),
            '--dataset',
            str(sim),
            '--drones_per_process',
            '4',
            '--checkpoint',
            checkpoint,
            '--monitor',
            '--monitor_out',
            str(tmp_path / 'monitor'),
            '--record',
            str(rec),
            '--log_dir',
            str(tmp_path / 'logs'),
            '--lockstep_timeout',
            '150',
        ],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    live_json, offline = tmp_path / 'live.json', tmp_path / 'offline'
    assert cli(['evaluate-recording', str(rec), '--ground-truth', str(sim / 'bag'), '--json', str(live_json)]) == 0
    assert cli(['register', str(sim), '--out', str(tmp_path / 'registration')]) == 0
    assert (
        cli(
            [
                'evaluate',
                str(sim),
                '--checkpoint',
                checkpoint,
                '--calibration',
                'registration',
                '--calibration-dir',
                str(tmp_path / 'registration'),
                '--out',
                str(offline),
                '--heatmaps',
                '0',
            ]
        )
        == 0
    )
    live, off = json.loads(live_json.read_text()), json.loads((offline / 'metrics.json').read_text())
    assert live['frames_without_tracks'] == []
    assert abs(live['detection']['moda'] - off['detection']['moda']) <= 0.01, (live['detection'], off['detection'])
    assert abs(live['tracking']['mota'] - off['tracking']['mota']) <= 0.01, (live['tracking'], off['tracking'])
    assert off['detection']['moda'] > 0.8  # the default checkpoint on registration homographies
