"""docs/ros-interface.md is what scripts/gen_ros_interface.py makes of the code, so it cannot drift."""

import importlib.util
from pathlib import Path

import pytest

from matrix_core import topics

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope='module')
def generator():
    spec = importlib.util.spec_from_file_location('gen_ros_interface', ROOT / 'scripts' / 'gen_ros_interface.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_page_is_what_the_code_gives(generator):
    committed = generator.DOC.read_text() if generator.DOC.is_file() else ''
    if committed != generator.render():
        pytest.fail(f'docs/ros-interface.md differs from the code: run `{generator.COMMAND}`', pytrace=False)


def test_every_node_is_found_with_its_parameters_and_endpoints(generator):
    nodes = {n.name: n for n in generator.find_nodes()}
    assert {'calib', 'register', 'fuse', 'graph_monitor', 'bag_player', 'dataset_player', 'recorder'} <= set(nodes)
    for node in nodes.values():
        assert node.endpoints, f'{node.name}: no publisher or subscription found'
    fuse = {(e.direction, e.topic) for e in nodes['fuse'].endpoints}
    assert ('publishes', topics.TRACKS) in fuse and ('subscribes', '{view}/' + topics.HOMOGRAPHY) in fuse
    assert ('publishes', topics.drone_topic('{view}', topics.HOMOGRAPHY)) in {
        (e.direction, e.topic) for e in nodes['register'].endpoints
    }


def test_the_nodes_use_the_types_topics_py_gives_their_topics(generator):
    """A node publishing or subscribing a topic of matrix_core.topics with another type would not match."""
    wrong = []
    for node in generator.find_nodes():
        for e in node.endpoints:
            if isinstance(e.topic, str):
                name = e.topic if e.topic.startswith('/') else '/' + e.topic
                try:
                    expected = topics.topic_type(name.replace('{view}', 'D1'))
                except KeyError:  # a topic topics.py does not list (e.g. /clock)
                    continue
                if e.msg_type != expected:
                    wrong.append(f'{node.name} {e.direction} {e.topic} as {e.msg_type}, topics.py: {expected}')
    assert not wrong, wrong
