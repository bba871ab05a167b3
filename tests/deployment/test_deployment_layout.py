"""The deployment layout (matrix_bringup.deployment): one host per drone and a ground station, built from the
one-host graph; what crosses each link and with which QoS. Pure data: no process, no bag is read."""

import pytest

from matrix_bringup.deployment import DOWN, GROUND, STREAMS, UP, deployment
from matrix_bringup.graph import BagFacts, GraphSettings, graph_nodes

FACTS = BagFacts(compressed=True, frames=5, has_ground_truth=True)
VIEWS = ['D1', 'D2', 'D3']


@pytest.fixture
def settings(matrix_sample):
    return lambda **kw: GraphSettings(bag='/data/bag', dataset=str(matrix_sample), views=VIEWS, **kw)


def test_each_drone_host_runs_its_own_camera_register_and_calib(settings):
    d = deployment(settings(record='/out/rec', monitor=True), FACTS)
    assert list(d.hosts) == [*VIEWS, GROUND] and d.drones == VIEWS
    for v in VIEWS:
        # calib + register: one process; link_sender: the camera's frames across the link
        assert [n.label for n in d.hosts[v]] == [f'{v}/drone', f'{v}/link_sender', f'{v}/bag_player']
        drone, sender, player = d.hosts[v]
        assert sender.executable == 'link_sender' and sender.namespace == v
        assert drone.parameters['views'] == [v] and drone.parameters['use_registration'] is True
        # the camera of this drone only, compressed, on the recorded timing (a camera does not wait)
        assert player.parameters['topics'] == [f'/{v}/image/compressed', f'/{v}/ground_truth/camera_info']
        assert player.parameters['lockstep'] is False and 'lockstep_topic' not in player.parameters
        assert player.parameters['wait_for_subscribers'] == 2  # drone and link_sender, both here
    separate = deployment(settings(record='/out/rec', monitor=True, drone_process=False), FACTS)
    assert [n.label for n in separate.hosts['D2']] == ['D2/calib', 'D2/register', 'D2/link_sender', 'D2/bag_player']
    assert separate.hosts['D2'][-1].parameters['wait_for_subscribers'] == 3
    assert [n.label for n in d.hosts[GROUND]] == ['fuse', 'recorder', 'graph_monitor']
    assert d.host_of('D2/drone') == 'D2' and d.host_of('fuse') == GROUND
    # no /clock across links: every host on its own clock
    assert not any(n.parameters.get('use_sim_time') for nodes in d.hosts.values() for n in nodes)


def test_the_same_processes_as_the_one_host_graph(settings):
    s = settings(record='/out/rec')
    one_host = [n.label for n in graph_nodes(s, FACTS)]
    deployed = [n.label for nodes in deployment(s, FACTS).hosts.values() for n in nodes]
    per_drone = [f'{v}/{n}' for v in VIEWS for n in ('bag_player', 'link_sender')]
    assert sorted(deployed) == sorted([label for label in one_host if label != 'bag_player'] + per_drone)


def test_what_crosses_each_link_and_its_qos(settings):
    d = deployment(settings(record='/out/rec', monitor=True), FACTS)
    assert list(d.links) == VIEWS
    link = {st.topic: st for st in d.links['D2']}
    assert set(link) == {
        'D2/link/image/compressed',
        'D2/link/dropped',
        'D2/homography',
        'D2/camera_info',
        'D2/pose',
        'D2/ground_truth/camera_info',
        '/diagnostics',
        '/tf',  # recorded: a recording opens in a viewer with the cameras placed
    }
    assert all(st.direction == UP for st in link.values())  # the ground sends nothing back but acks
    assert not any(st.direction == DOWN for streams in d.links.values() for st in streams)
    image = link['D2/link/image/compressed']  # link_sender's, not the camera's stream
    assert image.readers == ('fuse',) and 'dropped whole at the sender' in image.why
    assert link['D2/homography'].reliability == 'reliable'
    assert set(link['D2/homography'].readers) == {'fuse', 'recorder', 'graph_monitor'}
    assert image.reliability == 'best_effort'
    assert all(st.reliability == 'reliable' for t, st in link.items() if t != 'D2/link/image/compressed')
    assert all(st.why for st in link.values())
    # the fuse process asks for what the link table says: link_sender's images, best effort
    fuse = next(n for n in d.hosts[GROUND] if n.executable == 'fuse')
    assert fuse.parameters['qos'] == 'sensor_data' and fuse.parameters['image_kind'] == 'compressed'
    assert fuse.parameters['compressed_topic'] == '{view}/link/image/compressed'
    assert fuse.parameters['dropped_topic'] == '{view}/link/dropped' and link['D2/link/dropped'].readers == ('fuse',)
    assert 'D2/link/image/compressed' in d.describe() and 'best_effort' in d.describe()
    # the image budget of every link: none unless given
    assert d.hosts['D2'][1].parameters == {'link_mbit': 0.0}
    limited = deployment(settings(), FACTS, link_mbit=3.5)
    assert [limited.hosts[v][1].parameters['link_mbit'] for v in VIEWS] == [3.5] * 3
    one = deployment(settings(), FACTS, link_mbit={'D3': 2.0})
    assert [one.hosts[v][1].parameters['link_mbit'] for v in VIEWS] == [0.0, 0.0, 2.0]


def test_never_raw_images_and_a_minimal_link(settings):
    assert all('image_raw' not in st for st in STREAMS)
    with pytest.raises(ValueError, match='never raw 1080p'):
        deployment(settings(), BagFacts(compressed=False, frames=5, has_ground_truth=True))
    with pytest.raises(ValueError, match='one drone per host'):
        deployment(settings(drones_per_process=2), FACTS)
    # without recorder and monitor only what fuse needs crosses: the image and its geometry
    d = deployment(settings(), BagFacts(compressed=True, frames=5, has_ground_truth=False))
    assert [st.topic for st in d.links['D1']] == ['D1/link/image/compressed', 'D1/link/dropped', 'D1/homography']
    assert d.hosts['D1'][-1].parameters['topics'] == ['/D1/image/compressed']
    d = deployment(settings(input_kind='camera_info'), FACTS)
    assert [st.topic for st in d.links['D3']] == ['D3/link/image/compressed', 'D3/link/dropped', 'D3/camera_info']
