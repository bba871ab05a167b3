"""The live graph as data (matrix_bringup.graph) and the launch file built on it.

The launch file's description is evaluated with the real launch API (tests/helpers/launch_files.py, no
process started) and must produce exactly the processes of `graph_nodes`, which `run_graph` starts for real
(tests/system/test_run_graph.py); `ros2 launch` runs it for real in tests/system/test_ros2_launch.py."""

from pathlib import Path

import pytest
import yaml

from matrix_bringup.graph import BagFacts, GraphSettings, NodeSpec, graph_nodes
from matrix_core.settings import settings_fields
from launch.actions import RegisterEventHandler, SetEnvironmentVariable
from launch_ros.actions import Node
from launch_files import declared_arguments, launch, load

LAUNCH = Path(__file__).resolve().parents[2] / 'ros2_ws/src/matrix_bringup/launch/full_graph.launch.py'
FACTS = BagFacts(compressed=True, frames=5, has_ground_truth=True)
VIEWS = [f'D{i}' for i in range(1, 9)]


@pytest.fixture
def settings(matrix_sample):
    """GraphSettings for the real sample (its bag's facts are given, no bag is read)."""
    return lambda **kw: GraphSettings(bag='/data/bag', dataset=str(matrix_sample), **kw)


def test_per_drone_graph_has_one_calib_and_register_per_drone(settings):
    nodes = graph_nodes(settings(record='/out/rec', drone_process=False), FACTS)
    labels = [n.label for n in nodes]
    assert labels == [f'{v}/{exe}' for v in VIEWS for exe in ('calib', 'register')] + ['fuse', 'recorder', 'bag_player']
    calib = nodes[0]
    assert calib.parameters['views'] == ['D1'] and calib.parameters['compressed'] is True
    # calib follows the registration, waiting for it as long as the player waits for a frame (lockstep)
    assert calib.parameters['use_registration'] is True and calib.parameters['registration_wait_s'] == 120.0
    assert calib.parameters['config'].endswith('matrix_sample.yaml')  # not a simulated folder
    assert all(n.parameters.get('use_sim_time') for n in nodes if n.executable != 'bag_player')
    fuse = next(n for n in nodes if n.name == 'fuse')
    assert fuse.parameters['image_kind'] == 'compressed' and fuse.parameters['views'] == VIEWS
    recorder = next(n for n in nodes if n.name == 'recorder')
    assert {'/tracks', '/detections', '/D8/homography', '/D1/camera_info'} <= set(recorder.parameters['topics'])
    assert len(recorder.parameters['topics']) == len(recorder.parameters['types'])
    player = nodes[-1].parameters
    assert (player['lockstep_topic'], player['wait_for_subscribers']) == ('/tracks', 3)
    # lockstep: fuse waits for every view as long as the player waits (deterministic); else sync_timeout
    assert fuse.parameters['sync_timeout'] == player['lockstep_timeout'] == 120.0
    free = graph_nodes(settings(lockstep=False, sync_timeout=2.0, drone_process=False), FACTS)
    assert next(n for n in free if n.name == 'fuse').parameters['sync_timeout'] == 2.0
    assert 'lockstep_topic' not in free[-1].parameters and free[-1].parameters['lockstep'] is False
    assert 'registration_wait_s' not in free[0].parameters  # the node's default: a live drone is not waited for
    own = graph_nodes(settings(calib_registration=False, drone_process=False), FACTS)[0].parameters
    assert own['use_registration'] is False and 'registration_wait_s' not in own


def test_drone_process_hosts_calib_and_register_of_each_drone(settings):
    """The default: one process per drone runs both nodes under their own names, with both nodes' parameters."""
    nodes = graph_nodes(settings(record='/out/rec'), FACTS)
    assert [n.label for n in nodes] == [f'{v}/drone' for v in VIEWS] + ['fuse', 'recorder', 'bag_player']
    drone, separate = nodes[0], graph_nodes(settings(record='/out/rec', drone_process=False), FACTS)
    assert (drone.package, drone.executable, drone.namespace) == ('matrix_bringup', 'drone', 'D1')
    assert drone.parameters == {**separate[0].parameters, **separate[1].parameters}  # calib's and register's
    assert drone.param_files == separate[1].param_files  # register.yaml (`/**`: both nodes; views overridden)
    args = drone.ros_args()
    assert '__node:=drone' not in ' '.join(args) and args[:3] == ['--ros-args', '-r', '__ns:=/D1']
    # one image subscription per drone instead of calib's and register's: the player waits for drone and fuse
    assert nodes[-1].parameters['wait_for_subscribers'] == 2
    assert [n.label for n in nodes[len(VIEWS) :]] == [n.label for n in separate[2 * len(VIEWS) :]]


def test_drones_split_over_processes(settings):
    nodes = graph_nodes(settings(drones_per_process=3, drone_process=False), FACTS)
    calib = [n for n in nodes if n.executable == 'calib']
    assert [(n.label, n.parameters['views']) for n in calib] == [
        ('calib_1', ['D1', 'D2', 'D3']),
        ('calib_2', ['D4', 'D5', 'D6']),
        ('calib_3', ['D7', 'D8']),
    ]
    assert [n.label for n in nodes if n.executable == 'register'] == ['register_1', 'register_2', 'register_3']
    # drone processes: drone_2 hosts the nodes calib_2 and register_2 (node-specific remapping rules)
    drones = [n for n in graph_nodes(settings(drones_per_process=3), FACTS) if n.executable == 'drone']
    assert [(n.label, n.parameters['views']) for n in drones] == [
        ('drone_1', ['D1', 'D2', 'D3']),
        ('drone_2', ['D4', 'D5', 'D6']),
        ('drone_3', ['D7', 'D8']),
    ]
    assert drones[1].remaps == {'calib:__node': 'calib_2', 'register:__node': 'register_2'}
    assert drones[1].ros_args()[:5] == [
        '--ros-args',
        '-r',
        'calib:__node:=calib_2',
        '-r',
        'register:__node:=register_2',
    ]


def test_drone_processes_yield_to_fuse(settings):
    """On one computer the drone stage runs niced, so that the next frame's registrations wait for this frame's
    fusion: `nice -n N` before the executable (it execs it: the same process id, signals reach the node)."""
    for drone_process in (True, False):
        nodes = graph_nodes(settings(record='/out/rec', monitor=True, drone_process=drone_process), FACTS)
        drones = [n for n in nodes if n.executable in ('drone', 'calib', 'register')]
        assert len(drones) == (8 if drone_process else 16)
        assert all(n.prefix == ['nice', '-n', '10'] for n in drones)
        assert all(n.prefix == [] for n in nodes if n not in drones)  # fuse, recorder, monitor, player
    assert all(not n.prefix for n in graph_nodes(settings(drone_niceness=0), FACTS))
    for bad in (-1, 20):
        with pytest.raises(ValueError, match='drone_niceness'):
            settings(drone_niceness=bad)


def test_monitor_paces_lockstep_on_every_stage(settings):
    nodes = graph_nodes(
        settings(drones_per_process=0, monitor=True, views=['D1', 'D5']),
        BagFacts(compressed=False, frames=7, has_ground_truth=True),
    )
    assert [n.label for n in nodes] == ['drone', 'fuse', 'graph_monitor', 'bag_player']
    assert nodes[0].parameters['views'] == ['D1', 'D5'] and not nodes[0].remaps
    monitor = nodes[2].parameters
    assert monitor['wait_for'] == ['register', 'calib', 'tracks'] and monitor['expected_frames'] == 7
    player = nodes[-1].parameters
    # raw images: the monitor reads them too (drone and fuse read them; separate calib and register: one more)
    assert (player['lockstep_topic'], player['wait_for_subscribers']) == ('/graph_monitor/frame_done', 3)
    assert player['lockstep_window'] == 2  # the drones register the next frame while fuse fuses the last
    separate = graph_nodes(
        settings(drones_per_process=0, monitor=True, views=['D1', 'D5'], drone_process=False),
        BagFacts(compressed=False, frames=7, has_ground_truth=True),
    )
    assert [n.label for n in separate][:2] == ['calib', 'register'] and separate[-1].parameters[
        'wait_for_subscribers'
    ] == 4
    # a bag without ground truth: no evaluation, the graph runs without the monitor, lockstep on the tracks
    blind = graph_nodes(settings(monitor=True), BagFacts(compressed=False, frames=7, has_ground_truth=False))
    assert 'graph_monitor' not in [n.label for n in blind]
    assert blind[-1].parameters['lockstep_topic'] == '/tracks' and blind[-1].parameters['wait_for_subscribers'] == 2


def test_every_process_is_built_and_its_parameter_files_apply(node_executable, settings):
    """Parameter files use the `/**` key (they must reach /Dn/register and register_2) and name real parameters."""
    from matrix_bev_tracker.settings import FuseNodeSettings
    from matrix_register.settings import RegisterNodeSettings

    fields = {'register': RegisterNodeSettings, 'drone': RegisterNodeSettings, 'fuse': FuseNodeSettings}
    for node in graph_nodes(settings(record='/out/rec', monitor=True), FACTS):
        assert node_executable(node.package, node.executable).is_file()
        for path in node.param_files:
            ((key, body),) = yaml.safe_load(Path(path).read_text()).items()
            assert key == '/**', path
            assert set(body['ros__parameters']) <= {n for n, *_ in settings_fields(fields[node.executable])}, path


def test_ros_args_command_line():
    spec = NodeSpec(
        'matrix_calib',
        'calib',
        'calib',
        'D3',
        {'views': ['D3'], 'compressed': True, 'rate': 0.5, 'config': '/x.yaml'},
        ['/p.yaml'],
    )
    assert spec.ros_args() == [
        '--ros-args',
        '-r',
        '__node:=calib',
        '-r',
        '__ns:=/D3',
        '--params-file',
        '/p.yaml',
        '-p',
        'views:=[D3]',
        '-p',
        'compressed:=true',
        '-p',
        'rate:=0.5',
        '-p',
        'config:=/x.yaml',
    ]
    assert spec.label == 'D3/calib'
    # strings YAML would read as something else are quoted: a pattern in braces, a number, a boolean
    spec = NodeSpec(
        'matrix_bev_tracker',
        'fuse',
        'fuse',
        '',
        {'compressed_topic': '{view}/link/image/compressed', 'name': '12', 'flag': 'true', "it's": "it's"},
    )
    assert spec.ros_args()[3:] == [
        '-p',
        "compressed_topic:='{view}/link/image/compressed'",
        '-p',
        "name:='12'",
        '-p',
        "flag:='true'",
        '-p',
        "it's:=it's",
    ]


# --- the launch file, evaluated with the real launch API (tests/helpers/launch_files.py) -------------------
def test_launch_file_starts_the_graph_nodes(tmp_path):
    from matrix_core.cli.main import main as cli

    sim = tmp_path / 'sim'
    assert cli(['simulate', '--config', 'simple', '--frames', '2', '--fast', '--bag', '--out', str(sim)]) == 0
    description = load(LAUNCH)
    declared = declared_arguments(description)
    fields = {name: (default, help_text) for name, _, default, help_text in settings_fields(GraphSettings)}
    assert set(declared) == set(fields) | {'exit_at_end'} and declared['exit_at_end'][0] == 'true'
    assert all(text == fields[name][1] and text for name, (_, text) in declared.items() if name in fields)

    actions = launch(
        description,
        bag=str(sim / 'bag'),
        dataset=str(sim),
        views='D2,D4',
        record=str(tmp_path / 'rec'),
        dds_profile='/etc/fastdds.xml',
    )
    assert isinstance(actions[0], SetEnvironmentVariable)
    assert [s.text for s in actions[0].name] == ['FASTRTPS_DEFAULT_PROFILES_FILE']
    assert [s.text for s in actions[0].value] == ['/etc/fastdds.xml']
    launched = [a for a in actions if not isinstance(a, (SetEnvironmentVariable, RegisterEventHandler))]
    expected = graph_nodes(
        GraphSettings(
            bag=str(sim / 'bag'),
            dataset=str(sim),
            views=['D2', 'D4'],
            record=str(tmp_path / 'rec'),
            dds_profile='/etc/fastdds.xml',
        )
    )
    assert [(n.package, n.executable, n.name, n.namespace, n.remappings) for n in launched] == [
        (n.package, n.executable, n.name if n.renamed else Node.UNSPECIFIED_NODE_NAME, n.namespace, n.remaps)
        for n in expected
    ]
    assert [n.executable for n in launched][:2] == ['drone', 'drone']  # the default: a drone process per drone
    # the drone processes start through `nice` (GraphSettings.drone_niceness), the others as they are
    assert [n.prefix for n in launched] == [' '.join(n.prefix) for n in expected]
    assert launched[0].prefix == 'nice -n 10' and launched[-1].prefix == ''
    assert [n.parameters for n in launched] == [[*n.param_files, n.parameters] for n in expected]
    calib = launched[0].parameters[-1]
    assert calib['config'].endswith('sim_simple.yaml') and calib['compressed'] is False  # from the dataset and bag
    # the replay ends by itself: one exit handler per process, registered before the processes start
    handlers = [a for a in actions if isinstance(a, RegisterEventHandler)]
    assert len(handlers) == len(expected) and actions.index(handlers[-1]) < actions.index(launched[0])
    assert not any(
        isinstance(a, RegisterEventHandler)
        for a in launch(description, bag=str(sim / 'bag'), dataset=str(sim), views='D2,D4', exit_at_end='false')
    )
