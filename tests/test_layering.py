"""The joins between packages stay as designed (docs/ARCHITECTURE.md): thin nodes, one home per concept.

- a node package imports no other node package, and the calib node nothing from ``matrix_core.fusion``;
- every topic the graph wires (one host or deployed over hosts) is one ``matrix_core.topics`` defines, with
  the type it gives: the graph is built by ``matrix_bringup.graph`` and its topics looked up there;
- every other concept that crosses a package boundary has one implementation: these tests grep for the forms
  a second copy would take and name the one module that may hold each.
"""

import re
from pathlib import Path

import pytest
import yaml

from matrix_bringup.deployment import STREAMS, deployment
from matrix_bringup.graph import BagFacts, GraphSettings, graph_nodes
from matrix_core import topics
from tests.test_core_purity import imported_modules

SRC = Path(__file__).resolve().parents[1] / 'ros2_ws' / 'src'
NODE_PACKAGES = ('matrix_calib', 'matrix_register', 'matrix_bev_tracker', 'matrix_bringup', 'matrix_live_view')


def _sources():
    return [
        p for p in SRC.rglob('*.py') if '/test/' not in str(p) and '/launch/' not in str(p) and p.name != 'setup.py'
    ]


# The one place where the top layer composes node packages: a drone's calib and register in one process.
COMPOSERS = {SRC / 'matrix_bringup/matrix_bringup/drone.py': ('matrix_calib', 'matrix_register')}


def test_node_packages_do_not_import_each_other_and_calib_not_fusion():
    offenders = []
    for package in NODE_PACKAGES:
        for path in (SRC / package / package).glob('*.py'):
            for module in imported_modules(path):
                top = module.split('.')[0]
                if top in NODE_PACKAGES and top != package and top not in COMPOSERS.get(path, ()):
                    offenders.append(f'{path.name} imports {module}')
    for path in (SRC / 'matrix_calib').rglob('*.py'):
        offenders += [f'{path.name} imports {m}' for m in imported_modules(path) if m.startswith('matrix_core.fusion')]
    assert not offenders, offenders


# concept: (regular expression of a re-implementation, the files allowed to hold it)
ONE_HOME = {
    'K validity (det(K))': (r'det\(\s*K\s*\)', {'matrix_core/matrix_core/geometry/camera.py'}),
    'reading an image file': (r'cv2\.imread\(', {'matrix_core/matrix_core/datasets/base.py'}),
    'CameraInfo -> Camera': (r'np\.linalg\.solve\(\s*K\s*,\s*P', {'matrix_core/matrix_core/geometry/camera.py'}),
    'homography validity (condition number)': (r'linalg\.cond\(', {'matrix_core/matrix_core/register/registration.py'}),
    'the MATRIX area': (r'-30\.0,\s*30\.0,\s*0\.0', set()),
    'the encoder stride': (r'(?i)stride\s*=\s*4\b', {'matrix_core/matrix_core/bev/encoder.py'}),
    'a folder outside the package (matrix_core.locations)': (
        r'parents\[\d+\]',
        {'matrix_core/matrix_core/locations.py'},
    ),
    'the reference image width': (
        r'[/*]\s*1920\b|\b1920(\.0)?\s*[/*]|=\s*1920\b',
        {'matrix_core/matrix_core/reference_size.py'},
    ),
}


@pytest.mark.parametrize('concept', sorted(ONE_HOME))
def test_each_concept_has_one_home(concept):
    pattern, homes = ONE_HOME[concept]
    found = {str(p.relative_to(SRC)) for p in _sources() if re.search(pattern, p.read_text())}
    assert found <= homes, f'{concept} re-implemented in {sorted(found - homes)} (its home: {sorted(homes)})'


def test_one_home_detector_sees_a_copy(tmp_path):
    """The patterns above are not vacuous: each matches the form its old copies took."""
    samples = {
        'K validity (det(K))': 'abs(np.linalg.det(K)) < 1e-9',
        'reading an image file': 'cv2.imread(str(p))',
        'CameraInfo -> Camera': 'Rt = np.linalg.solve(K, P)',
        'homography validity (condition number)': 'np.linalg.cond(H) > 1e12',
        'the MATRIX area': '[0.0, -30.0, 30.0, 0.0]',
        'the encoder stride': 'STRIDE = 4',
        'the reference image width': 'scale = width / 1920',
        'a folder outside the package (matrix_core.locations)': "Path(__file__).resolve().parents[3] / 'config'",
    }
    for concept, text in samples.items():
        assert re.search(ONE_HOME[concept][0], text), concept


# (topic parameter, type parameter or None): the parameters of the graph's nodes that name topics
TOPIC_PARAMETERS = (('lockstep_topic', 'lockstep_type'), ('start_topic', None))
VIEWS = ['D1', 'D5']
BAG = BagFacts(
    compressed=True,
    frames=5,
    has_ground_truth=True,
    topics=tuple(
        sorted(
            [topics.PEDESTRIANS_TOPIC, topics.PEDESTRIAN_IDS_TOPIC]
            + [f(v) for v in VIEWS for f in (topics.camera_info_topic, topics.pose_topic)]
            + [topics.image_topic(v, compressed=True) for v in VIEWS]
        )
    ),
)


def _absolute(name: str, namespace: str, views) -> list:
    """The absolute names a node in ``namespace`` resolves ``name`` (a '{view}' pattern: for every view) to."""
    # (a node in a drone's namespace reads that drone's streams by their bare names: topics.drone_topic)
    names = [topics.drone_topic('' if v == namespace else v, name.replace('{view}/', '')) for v in views]
    names = names if '{view}/' in name else [name]
    return [n if n.startswith('/') else f'/{namespace}/{n}'.replace('//', '/') for n in names]


def _wired(node) -> list:
    """(absolute topic, type or None, where) of every topic a NodeSpec names: in its parameters and in its
    parameter files (``*_topic`` and the recorder's ``topics`` / ``types``)."""
    params = dict(node.parameters)
    for path in node.param_files:
        for section in (yaml.safe_load(Path(path).read_text()) or {}).values():
            params = {**section.get('ros__parameters', {}), **params}
    views = params.get('views') or [node.namespace]
    recorded = params.get('topics', ())
    types = params.get('types') or [None] * len(recorded)
    out = [(n, m, f'{node.label} topics') for n, m in zip(recorded, types)]
    paired = dict(TOPIC_PARAMETERS)
    for key, value in params.items():
        if key.endswith('_topic') and value:
            type_name = params.get(paired.get(key) or '')
            out += [(n, type_name, f'{node.label} {key}') for n in _absolute(value, node.namespace, views)]
    return out


def _graph(name: str, dataset: str) -> list:
    """The NodeSpecs of one way of running the graph."""
    with_all = GraphSettings(bag='b', dataset=dataset, views=VIEWS, record='rec', monitor=True, overlay=True)
    if name == 'deployed over hosts':
        deployed = deployment(GraphSettings(bag='b', dataset=dataset, views=VIEWS, record='rec'), BAG)
        return [n for nodes in deployed.hosts.values() for n in nodes]
    settings = {
        'one host, lockstep on the monitor': with_all,
        'one host, lockstep on the tracks': GraphSettings(bag='b', dataset=dataset, views=VIEWS, record='rec'),
        'one process per node': GraphSettings(
            bag='b', dataset=dataset, views=VIEWS, drone_process=False, record='rec', drones_per_process=0
        ),
    }[name]
    return graph_nodes(settings, BAG)


GRAPHS = (
    'one host, lockstep on the monitor',
    'one host, lockstep on the tracks',
    'one process per node',
    'deployed over hosts',
)


@pytest.mark.parametrize('graph', GRAPHS)
def test_every_topic_the_graph_wires_is_defined_in_topics(graph, matrix_sample):
    """Names and types of the graph built by ``graph.py`` (and its deployment) are those of ``topics.py``."""
    wired = [w for node in _graph(graph, str(matrix_sample)) for w in _wired(node)]
    assert len(wired) > 10, wired
    unknown, mistyped = [], []
    for name, type_name, where in wired:
        try:
            expected = topics.topic_type(name)
        except KeyError:
            unknown.append(f'{where}: {name}')
            continue
        if type_name is not None and type_name != expected:
            mistyped.append(f'{where}: {name} is {type_name}, topics.py says {expected}')
    assert not unknown and not mistyped, unknown + mistyped


def test_link_streams_have_the_types_of_topics():
    for stream, (type_name, *_) in STREAMS.items():
        name = stream if stream.startswith('/') else topics.absolute('D1', stream)
        assert topics.topic_type(name) == type_name, stream


def test_topic_lookup_refuses_what_topics_does_not_define():
    assert topics.topic_type(topics.absolute('D3', topics.HOMOGRAPHY)) == topics.HOMOGRAPHY_TYPE
    assert topics.topic_type(topics.graph_topic(topics.TRACKS)) == topics.TRACK_ARRAY_TYPE
    for name in ('/D1/homographies', '/tracks/D1', 'tracks', '/D1', '/detections_2d'):
        with pytest.raises(KeyError, match='not a topic'):
            topics.topic_type(name)
