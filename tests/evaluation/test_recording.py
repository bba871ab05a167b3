"""Scoring a recording against a sequence bag: perfect tracks score 100 %, a lost frame shows, and a
recorder-style bag (TrackArray tracks/detections + OccupancyGrid) is read with its embedded definitions."""

import json
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from matrix_core.cli.main import main as cli
from matrix_core.evaluation.recording import ground_truth_from_bag, read_recording_bag
from matrix_core.metrics import BevPoints, write_bev_points

MSG_DIR = Path(__file__).resolve().parents[2] / 'ros2_ws/src/matrix_msgs/msg'


@pytest.fixture(scope='module')
def sequence_bag(tmp_path_factory):
    out = tmp_path_factory.mktemp('recording') / 'sim'
    assert (
        cli(
            [
                'simulate',
                '--config',
                'complex',
                '--frames',
                '3',
                '--seed',
                '5',
                '--fast',
                '--image_ext',
                '.jpg',
                '--bag',
                '--compressed',
                '--out',
                str(out),
            ]
        )
        == 0
    )
    return out / 'bag'


def _write_recording(path, gt: BevPoints, drop_frame: int):
    store = get_typestore(Stores.ROS2_JAZZY)
    for msg in sorted(MSG_DIR.glob('*.msg')):
        store.register(get_types_from_msg(msg.read_text(), f'matrix_msgs/msg/{msg.stem}'))
    T = store.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {
            t: writer.add_connection(t, 'matrix_msgs/msg/TrackArray', typestore=store)
            for t in ('/tracks', '/detections')
        }
        grid = writer.add_connection('/bev_heatmap', 'nav_msgs/msg/OccupancyGrid', typestore=store)
        for frame in sorted(set(gt.frames.tolist()) - {drop_frame}):
            ns = int((1.0 + 0.5 * frame) * 1e9)
            header = T['std_msgs/msg/Header'](
                stamp=T['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9), frame_id='world'
            )
            tracks = []
            for k in gt.at(frame):
                tracks.append(
                    T['matrix_msgs/msg/Track'](
                        id=int(gt.ids[k]),
                        position=T['geometry_msgs/msg/Point'](x=gt.xy[k, 0], y=gt.xy[k, 1], z=0.0),
                        velocity=T['geometry_msgs/msg/Vector3'](x=0.0, y=0.0, z=0.0),
                        score=0.9,
                        age=frame,
                        misses=0,
                    )
                )
            for topic in conns:
                msg = T['matrix_msgs/msg/TrackArray'](header=header, tracks=tracks)
                writer.write(conns[topic], ns, store.serialize_cdr(msg, 'matrix_msgs/msg/TrackArray'))
            quat = T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0)
            pose = T['geometry_msgs/msg/Pose'](
                position=T['geometry_msgs/msg/Point'](x=-1.0, y=-31.0, z=0.0), orientation=quat
            )
            info = T['nav_msgs/msg/MapMetaData'](
                map_load_time=header.stamp, resolution=0.25, width=128, height=128, origin=pose
            )
            heat = T['nav_msgs/msg/OccupancyGrid'](header=header, info=info, data=np.zeros(128 * 128, np.int8))
            writer.write(grid, ns, store.serialize_cdr(heat, 'nav_msgs/msg/OccupancyGrid'))


def test_ground_truth_scores_perfectly(sequence_bag, tmp_path):
    gt = ground_truth_from_bag(sequence_bag)
    assert sorted(set(gt.frames.tolist())) == [0, 1, 2] and len(gt) == 3 * 40
    write_bev_points(tmp_path / 'tracks.txt', gt)
    out = tmp_path / 'm.json'
    assert (
        cli(
            [
                'evaluate-recording',
                str(tmp_path / 'tracks.txt'),
                '--ground-truth',
                str(sequence_bag),
                '--json',
                str(out),
            ]
        )
        == 0
    )
    m = json.loads(out.read_text())
    assert m['tracking']['mota'] == 1.0 and m['detection']['moda'] == 1.0 and m['detections_source'] == 'tracks'
    assert m['hota']['hota'] == 1.0 and m['hota']['ass_a'] == 1.0 and m['hota']['gate'] == 1.0


def test_recorder_bag_with_a_lost_frame(sequence_bag, tmp_path):
    gt = ground_truth_from_bag(sequence_bag)
    _write_recording(tmp_path / 'rec', gt, drop_frame=1)
    rec = read_recording_bag(tmp_path / 'rec')
    assert rec.track_frames == [0, 2] and rec.area == (-1.0, -31.0, 31.0, 1.0)
    out = tmp_path / 'm.json'
    assert (
        cli(['evaluate-recording', str(tmp_path / 'rec'), '--ground-truth', str(sequence_bag), '--json', str(out)]) == 0
    )
    m = json.loads(out.read_text())
    assert m['frames_without_tracks'] == [1] and m['detections_source'] == 'detections'
    assert m['detection']['recall'] == pytest.approx(2 / 3) and m['detection']['precision'] == 1.0
    # a lost frame costs detection, not association: DetA = DetRe = 2/3 (one frame of three missed), AssA < 1
    assert m['hota']['det_a'] == pytest.approx(2 / 3) and m['hota']['det_pr'] == 1.0
    assert m['hota']['ass_a'] < 1.0 and m['hota']['hota'] == pytest.approx(np.sqrt(2 / 3 * m['hota']['ass_a']))
    assert cli(['evaluate-recording', str(tmp_path / 'nothing'), '--ground-truth', str(sequence_bag)]) == 2
