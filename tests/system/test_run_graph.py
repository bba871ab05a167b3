"""System test: `run_graph` replays a bag of the real MATRIX sample in lockstep through the whole graph
(one drone process - calib + register - per drone, fuse, recorder, graph monitor: separate processes over DDS),
exactly as `full_graph.launch.py` would start it. What the graph published is scored: the monitor's
calibration/registration errors, and the recording's tracks against the bag's ground truth. Every frame
must reach every stage, and no process may outlive the run. The same replay serves clients of the standard
interfaces: a subscriber that knows only vision_msgs and tf2_msgs (its twins must equal what was recorded) and
a Foxglove WebSocket client of the live view (every kind of message decoded)."""

import csv
import json
import math
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from foxglove_client import FoxgloveClient

from matrix_core.bags import write_sequence_bag
from matrix_core.cli.main import main as cli
from matrix_core.datasets import MatrixDataset
from matrix_core.evaluation.recording import read_recording_bag

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ['D1', 'D5']
HELPERS = Path(__file__).resolve().parents[1] / 'helpers'


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
        '--live_view',
        '--live_view_port',
        str(port := _free_port()),
    ]  # the 1080p board search is slow on 2 loaded cores
    before = set(_node_processes())
    standard = tmp_path / 'standard.json'
    subscriber = subprocess.Popen(
        [sys.executable, str(HELPERS / 'standard_subscriber.py'), str(standard), *VIEWS],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert subscriber.stdout.readline().strip() == 'subscribed'
    watcher = FoxgloveClient(f'ws://127.0.0.1:{port}', timeout_s=300)
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    finally:
        watcher.close()
        subscriber.terminate()
        subscriber.wait(30)
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
            'live_view.log',
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
    _check_standard_twins(json.loads(standard.read_text()), rec)
    _check_live_view(watcher)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def _recorded(recording, names) -> dict:
    """topic -> [(stamp, message)] of the recording, deserialised with the types the bag itself carries."""
    from rosbags.highlevel import AnyReader

    found = {n: [] for n in names}
    with AnyReader([recording]) as reader:
        for conn, _, raw in reader.messages([c for c in reader.connections if c.topic in found]):
            msg = reader.deserialize(raw, conn.msgtype)
            found[conn.topic].append((round(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9, 6), msg))
    return found


def _check_standard_twins(got, recording):
    """What a vision_msgs / tf2_msgs subscriber received equals the recorded matrix_msgs and poses: every /tracks
    message has its Detection3DArray twin (same ids, positions within 1 mm), every drone's detections_2d its
    Detection2DArray, every pose its /tf transform (1 mm, 0.01 deg)."""
    assert got['modules'] == []  # it imported none of ours
    names = ['/tracks', *(f'/{v}/{s}' for v in VIEWS for s in ('detections_2d', 'pose'))]
    rec = _recorded(recording, names)
    twins = {round(m['stamp'], 6): m for m in got['tracks']}
    assert sorted(twins) == [stamp for stamp, _ in rec['/tracks']] and len(twins) == 5
    for stamp, msg in rec['/tracks']:
        twin = twins[stamp]
        assert twin['frame'] == 'world' and [d['id'] for d in twin['detections']] == [str(t.id) for t in msg.tracks]
        for d, t in zip(twin['detections'], msg.tracks):
            assert math.dist(d['xyz'][:2], (t.position.x, t.position.y)) < 1e-3 and d['class'] == ['person']
    assert any(m['detections'] for m in got['tracks']) and len(got['detections']) == 5
    for v in VIEWS:
        boxes = {round(m['stamp'], 6): m for m in got[f'{v}/detections_2d']}
        assert sorted(boxes) == [stamp for stamp, _ in rec[f'/{v}/detections_2d']]
        for stamp, msg in rec[f'/{v}/detections_2d']:
            twin = boxes[stamp]
            assert twin['frame'] == f'{v}/camera_optical'
            assert [d['id'] for d in twin['detections']] == [str(b.id) for b in msg.detections]
            for d, b in zip(twin['detections'], msg.detections):
                assert d['center'] == pytest.approx([(b.x_min + b.x_max) / 2, (b.y_min + b.y_max) / 2], abs=1e-6)
                assert d['size'] == pytest.approx([b.x_max - b.x_min, b.y_max - b.y_min], abs=1e-6)
        cameras = {round(t['stamp'], 6): t for t in got['tf'] if t['child'] == f'{v}/camera_optical'}
        assert sorted(cameras) == [stamp for stamp, _ in rec[f'/{v}/pose']] and cameras
        for stamp, pose in rec[f'/{v}/pose']:
            tf, p, q = cameras[stamp], pose.pose.position, pose.pose.orientation
            assert tf['parent'] == 'world' and math.dist(tf['translation'], (p.x, p.y, p.z)) < 1e-3
            cos_half = abs(float(np.dot(tf['rotation'], (q.x, q.y, q.z, q.w))))
            assert math.degrees(2 * math.acos(min(1.0, cos_half))) < 0.01
    assert [(t['parent'], t['child']) for t in got['tf_static']] == [('world', 'area')]


def _check_live_view(watcher):
    """The live view's channels as Foxglove lists them, and one decoded message of each kind."""
    assert not [e for e in watcher.errors if not e.startswith('closed')], watcher.errors  # closed: the replay ended
    overlays = [f'/{v}/overlay/compressed' for v in VIEWS]
    wanted = ['/live_view/tracks', '/live_view/scene', '/bev_heatmap', '/tf', '/tf_static', *overlays]
    assert set(wanted) <= set(watcher.channels) and all(watcher.counts.get(t) for t in wanted), watcher.counts
    schemas = {t: watcher.channels[t]['schemaName'] for t in wanted}
    assert schemas['/live_view/tracks'] == 'foxglove.SceneUpdate' and schemas['/bev_heatmap'] == 'foxglove.Grid'
    assert schemas['/tf'] == 'foxglove.FrameTransforms' and schemas[overlays[0]] == 'foxglove.CompressedImage'
    last = {t: m[-1][1] for t, m in watcher.messages.items()}
    assert {e.id for e in last['/live_view/scene'].entities} >= {'area', 'obstacles', *(f'camera/{v}' for v in VIEWS)}
    assert last['/bev_heatmap'].column_count > 0 and len(last['/bev_heatmap'].data) > 0
    assert last[overlays[0]].data[:2] == b'\xff\xd8'  # a JPEG
    assert {t.child_frame_id for t in last['/tf'].transforms} <= {f'{v}/camera_optical' for v in VIEWS}


def test_bad_settings_fail_clearly(matrix_sample, node_executable, tmp_path):
    run = subprocess.run(
        [
            str(node_executable('matrix_bringup', 'run_graph')),
            '--bag',
            str(tmp_path / 'none'),
            '--dataset',
            str(matrix_sample),  # a good dataset: the drones' references are read before the bag is opened
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
