"""live_view in its own process, fed over DDS by this test, watched by real WebSocket clients of the Foxglove
protocol: every channel listed and decoded (tracks with ids and trails, the scene, the heatmap grid, a drone's
calibration and overlay JPEG, the transforms); a client sending garbage, one vanishing mid-stream and a second
client: the node keeps serving the others and logs each cause."""

import socket

import cv2
import numpy as np
import pytest
import rclpy
from geometry_msgs.msg import Point
from matrix_msgs.msg import Track, TrackArray
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header
from tf2_msgs.msg import TFMessage

from foxglove_client import FoxgloveClient
from matrix_core import topics
from matrix_core.datasets import MatrixDataset
from matrix_core.datasets.base import read_image
from matrix_ros.conversions import camera_to_camera_info, camera_to_pose, seconds_to_stamp
from matrix_ros.qos import publisher_qos
from matrix_ros.standard_outputs import STATIC_TF_QOS
from matrix_ros.vision_messages import area_transform, pose_transform
from ros_helpers import spin_until, start_node, stop, wait_matched

pytestmark = pytest.mark.ros
CHANNELS = {
    '/live_view/scene',
    '/live_view/tracks',
    '/bev_heatmap',
    '/tf',
    '/tf_static',
    '/D1/camera_info',
    '/D1/overlay/compressed',
}


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def test_serves_every_channel_and_survives_bad_clients(matrix_sample, node_executable):
    ds, port = MatrixDataset(matrix_sample), _free_port()
    jpeg = cv2.imencode('.jpg', cv2.resize(read_image(ds.image_path('D1', 0)), (480, 270)))[1].tobytes()
    camera = ds.camera('D1', 0)
    view = start_node(node_executable('matrix_live_view', 'live_view'), f'port:={port}', 'views:=[D1]')
    rclpy.init()
    node = rclpy.create_node('live_view_feeder')
    clients = []
    try:
        pubs = {
            'tracks': node.create_publisher(TrackArray, '/tracks', publisher_qos()),
            'heatmap': node.create_publisher(OccupancyGrid, '/bev_heatmap', publisher_qos()),
            'tf': node.create_publisher(TFMessage, '/tf', publisher_qos()),
            'static': node.create_publisher(TFMessage, '/tf_static', STATIC_TF_QOS),
            'info': node.create_publisher(type(camera_to_camera_info(camera)), '/D1/camera_info', publisher_qos()),
            'overlay': node.create_publisher(CompressedImage, '/D1/overlay/compressed', publisher_qos()),
        }
        wait_matched(node, pubs.values(), [view], 60)
        pubs['static'].publish(TFMessage(transforms=[area_transform('world', (0.0, -30.0, 30.0, 0.0))]))
        url = f'ws://127.0.0.1:{port}'
        watcher = FoxgloveClient(url)
        second = FoxgloveClient(url, wanted=lambda t: t == '/live_view/tracks')
        rogue = FoxgloveClient(url)
        clients += [watcher, second, rogue]
        for c in clients:
            assert c.connected.wait(60) and not c.errors, c.errors
        frame = [0]

        def publish_frame():
            i = frame[0] = frame[0] + 1
            header = Header(stamp=seconds_to_stamp(1.0 + 0.5 * i), frame_id='world')
            pubs['tracks'].publish(
                TrackArray(header=header, tracks=[Track(id=5, score=0.9, position=Point(x=10.0 + 0.5 * i, y=-12.0))])
            )
            grid = OccupancyGrid(header=header)
            grid.info.resolution, grid.info.width, grid.info.height = 0.25, 4, 3
            grid.info.origin.position.x, grid.info.origin.position.y = -2.0, -32.0
            grid.info.origin.orientation.w = 1.0
            grid.data = [0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100, -1]
            pubs['heatmap'].publish(grid)
            optical = Header(stamp=header.stamp, frame_id=topics.optical_frame('D1'))
            pubs['info'].publish(camera_to_camera_info(camera, optical))
            pose = camera_to_pose(camera, header)
            pubs['tf'].publish(TFMessage(transforms=[pose_transform(pose, topics.optical_frame('D1'))]))
            pubs['overlay'].publish(CompressedImage(header=optical, format='jpeg', data=jpeg))

        def everything_arrived():
            publish_frame()
            return all(watcher.counts.get(t) for t in CHANNELS) and second.counts.get('/live_view/tracks')

        assert spin_until(node, everything_arrived, [view], 60), (watcher.counts, second.counts)
        assert CHANNELS <= set(watcher.channels)

        # one client sends garbage (text and binary) and vanishes without closing; the others go on
        rogue.send('{"op": "subscribe", "subscriptions": [{')
        rogue.send(b'\x99not a foxglove frame')
        rogue.abort()
        before = dict(watcher.counts), dict(second.counts)

        def still_served():
            publish_frame()
            return (
                watcher.counts['/live_view/tracks'] > before[0]['/live_view/tracks'] + 2
                and watcher.counts['/D1/overlay/compressed'] > before[0]['/D1/overlay/compressed']
                and second.counts['/live_view/tracks'] > before[1]['/live_view/tracks'] + 2
            )

        assert spin_until(node, still_served, [view], 60), (watcher.counts, second.counts)
        assert view.poll() is None
        _check_decoded(watcher, jpeg, camera)
    finally:
        for c in clients:
            c.close()
        node.destroy_node()
        rclpy.shutdown()
        log = stop(view)
    assert f'serving ws://127.0.0.1:{port}' in log, log
    assert 'Invalid message' in log and 'Unknown binary opcode' in log, log  # the garbage, named
    assert 'Connection reset' in log or 'Unregistered client' in log, log  # the client that vanished
    assert 'Traceback' not in log, log
    assert second.counts.get('/bev_heatmap') is None  # what a client did not subscribe it was never sent


def _check_decoded(watcher, jpeg, camera):
    """The last message of each channel says what was published."""
    last = {t: m[-1][1] for t, m in watcher.messages.items()}
    (track,) = last['/live_view/tracks'].entities
    assert track.id == 'track/5' and track.frame_id == 'world' and track.texts[0].text == '5'
    assert track.cylinders[0].pose.position.y == -12.0 and track.cylinders[0].pose.position.x > 10.5
    trail = track.lines[0].points  # the track's last positions, oldest first, the newest where it is
    assert len(trail) > 1 and trail[-1].x == track.cylinders[0].pose.position.x and trail[0].x < trail[-1].x
    assert [d.type for d in last['/live_view/tracks'].deletions] == [1]  # ALL: the previous frame's go
    scene = {e.id: e for e in last['/live_view/scene'].entities}
    assert {'area', 'obstacles', 'camera/D1'} <= set(scene)
    assert len(scene['area'].lines[0].points) == 5 and len(scene['obstacles'].cubes) == 1  # the MATRIX block
    frustum = scene['camera/D1']
    assert frustum.frame_id == 'D1/camera_optical' and frustum.frame_locked and len(frustum.lines[0].points) == 16
    grid = last['/bev_heatmap']
    assert (grid.column_count, grid.row_stride, grid.cell_size.x, grid.pose.position.y) == (4, 4, 0.25, -32.0)
    assert list(np.frombuffer(grid.data, np.int8)) == [0, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100, -1]
    image = last['/D1/overlay/compressed']
    assert image.data == jpeg and image.format == 'jpeg' and image.frame_id == 'D1/camera_optical'
    calib = last['/D1/camera_info']
    assert list(calib.K) == pytest.approx(camera.K.ravel().tolist()) and calib.width == camera.width
    (tf,) = last['/tf'].transforms
    assert (tf.parent_frame_id, tf.child_frame_id) == ('world', 'D1/camera_optical')
    assert [tf.translation.x, tf.translation.y, tf.translation.z] == pytest.approx(camera.center.tolist())
    static = last['/tf_static'].transforms
    assert [(t.parent_frame_id, t.child_frame_id, t.translation.y) for t in static] == [('world', 'area', -30.0)]
