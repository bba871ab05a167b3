"""The ROS 2 user's path, for real: `ros2 launch` of every launch file of the workspace (the ros2 CLI and
launch of a ROS install, or those scripts/build_cli.sh builds here), as the README shows them.

- full_graph.launch.py replays a bag of the real sample through the whole graph and ends by itself: exit 0,
  the recorder's bag closed and scored for every frame, every process stopped; non-zero with the reason on
  a lockstep timeout or a node that died, and on bad arguments before any process starts; a drone whose
  reference cannot be read is left out, the others replayed, and the launch exits 1 naming it;
- dataset_player.launch.py, calib.launch.py and register.launch.py together on the real sample: one drone's
  images, camera_info and homography arrive, with the launch arguments as the nodes' parameters.
"""

import json
import os
import re
import subprocess

import pytest
import rclpy
from rclpy.node import Node
from rclpy.qos import QoSDurabilityPolicy, QoSProfile

import ros_helpers
from matrix_core.cli.main import main as cli

pytestmark = pytest.mark.ros
LAUNCH = ('launch', 'matrix_bringup', 'full_graph.launch.py')


def _started_and_stopped(output: str) -> tuple:
    """The pids `ros2 launch` started, and those it saw exit, from its log lines."""
    started = set(re.findall(r'process started with pid \[(\d+)\]', output))
    ended = set(re.findall(r'process has (?:finished cleanly|died) \[pid (\d+)', output))
    return started, ended


@pytest.mark.slow
def test_full_graph_replay_of_the_real_sample_ends_by_itself(matrix_sample, tmp_path):
    bag, rec, monitor = tmp_path / 'bag', tmp_path / 'rec', tmp_path / 'monitor'
    assert cli(['bag', str(matrix_sample), '--out', str(bag)]) == 0  # as the README makes it
    run = _launch_graph(
        f'bag:={bag}',
        f'dataset:={matrix_sample}',
        f'record:={rec}',
        'monitor:=true',
        f'monitor_out:={monitor}',
        'drones_per_process:=0',
    )
    out = run.stdout
    assert run.returncode == 0, out[-8000:]
    assert 'replay done: the bag was played and the monitor wrote its scores' in out, out[-4000:]
    assert 'played 5 frames' in out and 'lockstep: only' not in out and 'Traceback' not in out
    assert f'closed {rec}:' in out  # the recorder closed its bag on the launch's SIGINT
    started, ended = _started_and_stopped(out)
    assert len(started) == 5 and started == ended, (started, ended)  # drone, fuse, recorder, monitor, player
    assert not [pid for pid in started if os.path.exists(f'/proc/{pid}')]

    summary = [line.split() for line in (monitor / 'graph_summary.txt').read_text().splitlines()]
    assert ['all', '40'] in [row[:2] for row in summary]  # 8 views x 5 frames scored live
    metrics = tmp_path / 'metrics.json'
    scored = subprocess.run(
        ['matrix-tracker', 'evaluate-recording', str(rec), '--ground-truth', str(bag), '--json', str(metrics)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert scored.returncode == 0, scored.stdout + scored.stderr
    assert 'frames without a TrackArray: none' in scored.stdout
    result = json.loads(metrics.read_text())
    assert result['detection']['moda'] > 0.8 and result['tracking']['mota'] > 0.8, result


def _launch_graph(*arguments: str, timeout_s: float = 600.0) -> subprocess.CompletedProcess:
    """`ros2 launch matrix_bringup full_graph.launch.py ARGUMENTS...` to its end."""
    return ros_helpers.ros2(*LAUNCH, *arguments, timeout_s=timeout_s)


@pytest.fixture(scope='module')
def small_bag(tmp_path_factory):
    """A simulated 2-frame sequence at 640x360 and its bag; the tests replay two of its drones (seconds)."""
    sim = tmp_path_factory.mktemp('sim') / 'sim'
    assert cli(['simulate', '--config', 'simple', '--frames', '2', '--fast', '--bag', '--out', str(sim)]) == 0
    return sim


@pytest.mark.parametrize(
    'arguments, message',
    [
        (['bag:=/nonexistent/bag'], 'not a rosbag2 folder'),
        (['views:=[D9]'], 'no images of view(s) D9 in this bag'),
        (['dataset:=/nonexistent/dataset'], 'dataset folder not found'),
        (['input_kind:=lidar'], 'input_kind must be homography or camera_info'),
        (['lockstep_timout:=3'], "unknown launch argument(s) 'lockstep_timout' (did you mean 'lockstep_timeout'?)"),
    ],
)
def test_full_graph_argument_errors_say_what_is_wrong_before_anything_starts(small_bag, arguments, message):
    given = dict(
        a.split(':=', 1) for a in [f'bag:={small_bag / "bag"}', f'dataset:={small_bag}', 'views:=[D1,D2]', *arguments]
    )
    run = _launch_graph(*(f'{k}:={v}' for k, v in given.items()), timeout_s=120)
    assert run.returncode != 0 and message in run.stdout, run.stdout[-3000:]
    assert 'process started' not in run.stdout


@pytest.mark.slow
@pytest.mark.parametrize(
    'arguments, reason',
    [
        (['lockstep_timeout:=0.01'], 'bag_player exited with code 3 (lockstep timed out for some frame)'),
        (['checkpoint:=/nonexistent/model.pt'], 'fuse exited early'),
    ],
)
def test_full_graph_exits_non_zero_on_a_lockstep_timeout_or_a_dead_node(small_bag, tmp_path, arguments, reason):
    run = _launch_graph(
        f'bag:={small_bag / "bag"}',
        f'dataset:={small_bag}',
        'views:=[D1,D2]',
        'drones_per_process:=0',
        f'record:={tmp_path / "rec"}',
        *arguments,
        timeout_s=300,
    )
    assert run.returncode == 1 and reason in run.stdout, run.stdout[-6000:]
    started, ended = _started_and_stopped(run.stdout)
    assert started and started == ended, (started, ended)  # every node stopped all the same
    assert f'closed {tmp_path / "rec"}:' in run.stdout  # and the recording closed


@pytest.mark.slow
def test_full_graph_without_a_drone_whose_reference_is_unreadable(small_bag, tmp_path):
    """D2's reference image is two bytes of text: the launch leaves D2 out before anything starts, replays the
    bag through D1, fuse and the recorder, names D2 in its ``replay done:`` line and exits 1 (run_graph: 5)."""
    import shutil

    data = tmp_path / 'sim'
    shutil.copytree(small_bag, data, copy_function=os.symlink, ignore=shutil.ignore_patterns('bag'))
    (reference,) = (data / 'reference' / 'image_subsets' / 'D2').glob('0000.*')
    reference.unlink()
    reference.write_text('x\n')
    run = _launch_graph(
        f'bag:={small_bag / "bag"}',
        f'dataset:={data}',
        'views:=[D1,D2]',
        'drones_per_process:=0',
        f'record:={tmp_path / "rec"}',
        timeout_s=300,
    )
    out = run.stdout
    assert run.returncode == 1, out[-6000:]
    done = [line for line in out.splitlines() if 'replay done: ' in line]
    assert len(done) == 1 and 'the bag was played' in done[0], out[-6000:]
    assert f'ran without drone(s) D2: D2 left out (reference: cannot decode image {reference}' in done[0], done
    assert 'Caught exception in launch' in out and out.count('ran without drone(s) D2: ') == 2, out[-6000:]
    assert 'Traceback' not in out
    started, ended = _started_and_stopped(out)
    assert len(started) == 4 and started == ended, (started, ended)  # D1's drone, fuse, recorder, player
    assert f'closed {tmp_path / "rec"}:' in out  # the recording of D1's frames closed
    assert (tmp_path / 'rec.tracks.txt').read_text().startswith('0 ')


@pytest.mark.slow
def test_full_graph_replays_the_frames_before_a_bag_is_cut(small_bag, tmp_path):
    """A bag cut in its second frame: the graph starts, the first frame is played, fused and
    recorded, then the launch exits 1 saying the bag is damaged; every node stopped, the recording closed."""
    import shutil

    from matrix_core.bags.salvage import mcap_file

    cut = tmp_path / 'cut'
    shutil.copytree(small_bag / 'bag', cut)
    f = mcap_file(cut)
    f.write_bytes(f.read_bytes()[: int(f.stat().st_size * 0.75)])
    run = _launch_graph(
        f'bag:={cut}',
        f'dataset:={small_bag}',
        'views:=[D1,D2]',
        'drones_per_process:=0',
        f'record:={tmp_path / "rec"}',
        timeout_s=300,
    )
    assert run.returncode == 1, run.stdout[-6000:]
    assert (
        'bag_player exited with code 4 (the bag is damaged: only the frames before the damage were played)'
        in run.stdout
    ), run.stdout[-6000:]
    assert 'played 1 frames up to frame 0' in run.stdout and 'messages before the damage' in run.stdout
    started, ended = _started_and_stopped(run.stdout)
    assert started and started == ended, (started, ended)
    assert f'closed {tmp_path / "rec"}:' in run.stdout
    assert (tmp_path / 'rec.tracks.txt').read_text().startswith('0 ')  # the played frame was fused, tracked


@pytest.mark.slow
def test_node_launch_files_on_the_real_sample(matrix_sample):
    """The three node launch files of docs/running-the-graph.md, one drone: images in, camera_info and
    homography out."""
    sample = f'dataset:={matrix_sample}'
    launches = [
        ros_helpers.start_ros2(
            'launch', 'matrix_calib', 'calib.launch.py', f'prior_dataset:={matrix_sample}', 'views:=[D1]'
        ),
        ros_helpers.start_ros2(
            'launch', 'matrix_register', 'register.launch.py', f'reference_dataset:={matrix_sample}', 'views:=[D1]'
        ),
        # slow enough for a loaded machine; repeats until the test has what it waits for
        ros_helpers.start_ros2(
            'launch',
            'matrix_ros',
            'dataset_player.launch.py',
            sample,
            'views:=[D1]',
            'rate:=0.25',
            'loop:=true',
            'wait_for_subscribers:=2',
        ),
    ]
    rclpy.init()
    node = Node('launch_files_probe')
    try:
        from matrix_msgs.msg import HomographyStamped
        from sensor_msgs.msg import CameraInfo

        got = {}
        history = QoSProfile(depth=10, durability=QoSDurabilityPolicy.TRANSIENT_LOCAL)
        for topic, msg_type in (('/D1/camera_info', CameraInfo), ('/D1/homography', HomographyStamped)):
            node.create_subscription(msg_type, topic, lambda m, t=topic: got.setdefault(t, m), history)
        ok = ros_helpers.spin_until(node, lambda: len(got) == 2, launches, timeout_s=240)
        outputs = ros_helpers.interrupt_all(launches) if not ok else None
        assert ok, f'got {sorted(got)}\n' + '\n'.join(o[-3000:] for o in outputs)
        assert got['/D1/homography'].header.frame_id and len(got['/D1/camera_info'].p) == 12
        for name, value in (('/calib', 'views'), ('/register', 'views')):  # launch arguments -> typed parameters
            shown = ros_helpers.ros2_graph('param', 'get', name, value).stdout
            assert "String values are: ['D1']" in shown, shown
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
        outputs = ros_helpers.interrupt_all(launches)
    for output in outputs:
        assert 'Traceback' not in output, output[-3000:]
