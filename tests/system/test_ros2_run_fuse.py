"""`ros2 run` as the README shows it: `fuse --ros-args --params-file ...` fed by `ros2 run matrix_ros
bag_player`, with `ros2 topic echo /tracks` in another process as "the other robotics stack", then `ros2 param
get/set` on the running node (the live parameters change, the others refuse with a reason); and
`ros2 run matrix_ros dataset_player` on the real sample."""

import pytest

import ros_helpers
from matrix_bringup.graph import BagFacts
from matrix_core.cli.main import main as cli

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ['D1', 'D2']


def test_fuse_started_with_ros2_run_feeds_another_process_and_takes_live_parameters(tmp_path):
    sim = tmp_path / 'sim'
    assert cli(['simulate', '--config', 'simple', '--frames', '2', '--fast', '--bag', '--out', str(sim)]) == 0
    prefix = ros_helpers.ros2('pkg', 'prefix', 'matrix_bev_tracker').stdout.strip()
    params = f'{prefix}/share/matrix_bev_tracker/config/fuse.yaml'
    # fuse builds RViz markers only while someone subscribes: this echo, in the graph before fuse starts (started
    # beside fuse, the CLI was not yet matched when fuse had fused both frames of a loaded CI run)
    markers = ros_helpers.start_ros2(
        'topic',
        'echo',
        '--no-daemon',
        '--once',
        '--qos-reliability',
        'reliable',
        '/markers',
        'visualization_msgs/msg/MarkerArray',
    )
    try:
        ros_helpers.wait_for(
            lambda: 'Subscription count: 1' in ros_helpers.ros2_graph('topic', 'info', '/markers').stdout,
            120,
            'the /markers echo to subscribe',
        )
    except AssertionError:
        ros_helpers.interrupt_all([markers])
        raise
    # geometry: the bag's ground-truth CameraInfo (no calib or register needed to feed fuse)
    fuse = ros_helpers.start_ros2(
        'run',
        'matrix_bev_tracker',
        'fuse',
        '--ros-args',
        '--params-file',
        params,
        '-p',
        f'views:=[{",".join(VIEWS)}]',
        '-p',
        'input_kind:=camera_info',
        '-p',
        "camera_info_topic:='{view}/ground_truth/camera_info'",
        '-p',
        'use_sim_time:=true',
    )
    # transient local, as the graph's observers: it gets the tracks whenever it matched
    echo = ros_helpers.start_ros2(
        'topic',
        'echo',
        '--no-daemon',
        '--once',
        '--qos-durability',
        'transient_local',
        '--qos-reliability',
        'reliable',
        '/tracks',
        'matrix_msgs/msg/TrackArray',
    )
    # fuse builds markers only for a matched subscriber: let discovery pair fuse's /markers with the echo
    # before the first frame, or a loaded machine fuses both frames before they match
    ros_helpers.wait_for(
        lambda: 'Publisher count: 1' in ros_helpers.ros2_graph('topic', 'info', '/markers').stdout,
        120,
        'fuse to offer /markers to the echo',
    )
    topics = ','.join(BagFacts.read(str(sim / 'bag'), VIEWS).topics)
    player = ros_helpers.start_ros2(
        'run',
        'matrix_ros',
        'bag_player',
        '--ros-args',
        '-p',
        f'bag:={sim / "bag"}',
        '-p',
        f'topics:=[{topics}]',
        '-p',
        'wait_for_subscribers:=1',
        '-p',
        'lockstep:=true',
        '-p',
        'lockstep_topic:=/tracks',
        '-p',
        'lockstep_type:=matrix_msgs/msg/TrackArray',
    )
    try:
        ros_helpers.wait_for(
            lambda: player.poll() is not None or fuse.poll() is not None, 240, 'the player to play the bag'
        )
        assert fuse.poll() is None, ros_helpers.finish(fuse)[-3000:]
        played = ros_helpers.finish(player)
        echoed = ros_helpers.finish(echo, timeout_s=60)
        assert player.returncode == 0 and 'played 2 frames' in played, played[-3000:]
        assert echo.returncode == 0 and 'frame_id: world' in echoed and 'tracks:' in echoed, echoed[-3000:]
        echoed = ros_helpers.finish(markers, timeout_s=60)
        assert markers.returncode == 0 and 'ns: tracks' in echoed and 'ns: track_ids' in echoed, echoed[-3000:]

        assert '/fuse' in ros_helpers.ros2_graph('node', 'list').stdout.split()
        get = ros_helpers.ros2_graph('param', 'get', '/fuse', 'tracker_reset_gap_s').stdout
        assert 'Double value is: 5.0' in get, get
        changed = ros_helpers.ros2_graph('param', 'set', '/fuse', 'tracker_reset_gap_s', '2.5').stdout
        assert 'Set parameter successful' in changed, changed
        assert 'Double value is: 2.5' in ros_helpers.ros2_graph('param', 'get', '/fuse', 'tracker_reset_gap_s').stdout
        invalid = ros_helpers.ros2_graph('param', 'set', '/fuse', 'tracker_reset_gap_s', '-1.0').stdout
        assert 'Setting parameter failed' in invalid and 'reset gaps > 0' in invalid, invalid
        fixed = ros_helpers.ros2_graph('param', 'set', '/fuse', 'sync_timeout', '3.0').stdout
        assert 'Setting parameter failed' in fixed and 'read-only' in fixed, fixed
        shown = ros_helpers.ros2('interface', 'show', 'matrix_msgs/msg/TrackArray').stdout
        assert 'Track[] tracks' in shown, shown
    finally:
        fused, *_ = ros_helpers.interrupt_all([fuse, echo, markers, player])
    assert 'published 2 frames' in fused and 'parameters changed: tracker_reset_gap_s=2.5' in fused, fused[-3000:]
    assert 'Traceback' not in fused, fused[-3000:]


def test_dataset_player_started_with_ros2_run(matrix_sample):
    player = ros_helpers.start_ros2(
        'run',
        'matrix_ros',
        'dataset_player',
        '--ros-args',
        '-p',
        f'dataset:={matrix_sample}',
        '-p',
        'views:=[D1]',
        '-p',
        'loop:=true',
    )
    try:
        echo = ros_helpers.ros2(
            'topic',
            'echo',
            '--no-daemon',
            '--once',
            '--qos-durability',
            'transient_local',
            '/D1/ground_truth/camera_info',
            'sensor_msgs/msg/CameraInfo',
            timeout_s=120,
        )
        assert echo.returncode == 0 and 'width: 1920' in echo.stdout, echo.stdout[-3000:]
    finally:
        output = ros_helpers.interrupt(player)
    assert 'Traceback' not in output, output[-3000:]
