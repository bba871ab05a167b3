"""System test: a simulated sequence bag replays in lockstep through the `fuse` node while the `recorder`
records its output, each in its own process over DDS; the recording, scored against the bag's ground
truth, must match the offline `matrix-tracker evaluate` of the same checkpoint on the same frames, in the
BEV and in the image plane (every drone's detections_2d against the annotated boxes)."""

import json
import os
from pathlib import Path

import pytest

from matrix_core.bags import bag_topics
from matrix_core.cli.main import main as cli
from matrix_core.evaluation.recording import read_recording_bag
from ros_helpers import start_node, stop, wait_for

pytestmark = [pytest.mark.ros, pytest.mark.slow]
FRAMES = 12
# Whole images in shared memory and a short DDS heartbeat: without it a lost fragment costs 3 s (see the file).
DDS_PROFILE = Path(__file__).resolve().parents[2] / 'ros2_ws/src/matrix_bringup/config/fastdds.xml'


def _start(node_executable, pkg, exe, *params):
    profile = os.environ.get('FASTRTPS_DEFAULT_PROFILES_FILE', str(DDS_PROFILE))  # the environment's wins
    return start_node(node_executable(pkg, exe), *params, env={'FASTRTPS_DEFAULT_PROFILES_FILE': profile})


def test_live_graph_equals_offline(node_executable, tmp_path):
    sim = tmp_path / 'sim'
    # .png: the folder (offline) holds exactly the pixels the bag (live) carries
    assert (
        cli(
            [
                'simulate',
                '--config',
                'complex',
                '--frames',
                str(FRAMES),
                '--seed',
                '7',
                '--fast',
                '--image_ext',
                '.png',
                '--bag',
                '--out',
                str(sim),
            ]
        )
        == 0
    )
    assert (
        cli(
            ['evaluate', str(sim), '--checkpoint', _checkpoint(), '--out', str(tmp_path / 'offline'), '--heatmaps', '0']
        )
        == 0
    )
    offline = json.loads((tmp_path / 'offline' / 'metrics.json').read_text())

    rec = tmp_path / 'rec'
    topics = bag_topics(sim / 'bag')
    images = sorted(t for t in topics if t.endswith('image_raw'))
    infos = sorted(t for t in topics if t.endswith('ground_truth/camera_info'))
    fuse = _start(
        node_executable,
        'matrix_bev_tracker',
        'fuse',
        'input_kind:=camera_info',
        'camera_info_topic:=/{view}/ground_truth/camera_info',
        'use_sim_time:=true',
        'sync_timeout:=30.0',
        f'scene_dataset:={sim}',
    )  # lockstep: never cut a frame short (DDS retransmits after ~3 s)
    boxes = [t.replace('image_raw', 'detections_2d') for t in images]
    recorder = _start(
        node_executable,
        'matrix_ros',
        'recorder',
        f'out:={rec}',
        f'topics:=[/tracks,/detections,/bev_heatmap,{",".join(boxes)}]',
        'types:=[matrix_msgs/msg/TrackArray,matrix_msgs/msg/TrackArray,nav_msgs/msg/OccupancyGrid,'
        + ','.join(['matrix_msgs/msg/Detection2DArray'] * len(boxes))
        + ']',
        'tracks_topic:=/tracks',
        f'mot_file:={tmp_path / "tracks.txt"}',
        'use_sim_time:=true',
    )
    _wait_for_endpoints('/tracks', publishers=1, subscribers=1)  # fuse -> recorder, before frame 0 leaves
    player = _start(
        node_executable,
        'matrix_ros',
        'bag_player',
        f'bag:={sim / "bag"}',
        'wait_for_subscribers:=1',
        f'topics:=[{",".join(images + infos)}]',
        'lockstep:=true',
        'lockstep_topic:=/tracks',
        'lockstep_type:=matrix_msgs/msg/TrackArray',
        'lockstep_timeout:=60.0',
    )
    mot = tmp_path / 'tracks.txt'
    try:
        player_out = player.communicate(timeout=240)[0]
        # the recorder got the last frame's tracks (its MOT text is flushed per message)
        wait_for(
            lambda: mot.is_file() and any(line.split()[0] == str(FRAMES - 1) for line in mot.read_text().splitlines()),
            30,
            f'the last frame in {mot}',
        )
    finally:  # upstream first: the recorder takes the rest of what fuse published while fuse shuts down
        fuse_out, rec_out = stop(fuse), stop(recorder)
        if player.poll() is None:
            stop(player)
    assert f'played {FRAMES} frames' in player_out and 'lockstep: only' not in player_out, player_out + fuse_out
    assert 'missing' not in fuse_out and 'Traceback' not in fuse_out, fuse_out
    assert f'published {FRAMES} frames' in fuse_out, fuse_out

    recording = read_recording_bag(rec)
    assert recording.track_frames == list(range(FRAMES)), rec_out  # no frame lost
    live_json = tmp_path / 'live.json'
    assert (
        cli(
            [
                'evaluate-recording',
                str(rec),
                '--ground-truth',
                str(sim / 'bag'),
                '--json',
                str(live_json),
                '--dataset',
                str(sim),
            ]
        )
        == 0
    )
    live = json.loads(live_json.read_text())
    assert live['detections_source'] == 'detections' and live['frames_without_tracks'] == []
    for part, key in (('detection', 'moda'), ('tracking', 'mota'), ('detection', 'recall')):
        assert abs(live[part][key] - offline[part][key]) <= 0.01, (key, live[part], offline[part])
    assert offline['detection']['moda'] > 0.5  # the shipped model detects the crowd at all
    # image plane: the same boxes live (CameraInfo) and offline (the camera its homography implies)
    live_2d, offline_2d = live['image_plane']['per_drone'], offline['image_plane']
    assert set(live_2d) == set(offline_2d) == {f'D{k}' for k in range(1, 9)} | {'all'}
    for key in ('precision', 'recall', 'mota', 'idf1'):
        assert abs(live_2d['all'][key] - offline_2d['all'][key]) <= 0.01, (key, live_2d['all'], offline_2d['all'])
    assert live['image_plane']['ids_in_tracks'] == 1.0  # every drone's ids are the BEV track ids
    # the recorder's MOT text scores the same tracks
    mot_json = tmp_path / 'mot.json'
    assert (
        cli(
            [
                'evaluate-recording',
                str(tmp_path / 'tracks.txt'),
                '--ground-truth',
                str(sim / 'bag'),
                '--area',
                *map(str, recording.area),
                '--json',
                str(mot_json),
            ]
        )
        == 0
    )
    assert json.loads(mot_json.read_text())['tracking'] == pytest.approx(live['tracking'], abs=1e-3)  # 4-decimal text


def _wait_for_endpoints(topic: str, publishers: int, subscribers: int, timeout: float = 60.0) -> None:
    """Until this process's DDS graph shows the endpoints of two other processes. Their own matching cannot be
    seen from here; the recorder asks for the publishers' history, so a late match loses nothing."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context)
    node = rclpy.create_node('fuse_graph_test_probe', context=context)
    try:  # the graph cache fills without spinning
        wait_for(
            lambda: node.count_publishers(topic) >= publishers and node.count_subscribers(topic) >= subscribers,
            timeout,
            f'{publishers} publishers and {subscribers} subscribers on {topic}',
        )
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def _checkpoint() -> str:
    from matrix_core.fusion.settings import shipped_checkpoint

    return str(shipped_checkpoint())
