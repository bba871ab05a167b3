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
    'absolute per-drone topic names': (r"f'/\{view\}/", {'matrix_core/matrix_core/topics.py'}),
    'the MATRIX area': (r'-30\.0,\s*30\.0,\s*0\.0', set()),
    'the encoder stride': (r'(?i)stride\s*=\s*4\b', {'matrix_core/matrix_core/bev/encoder.py'}),
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
        'absolute per-drone topic names': "f'/{view}/homography'",
        'the MATRIX area': '[0.0, -30.0, 30.0, 0.0]',
        'the encoder stride': 'STRIDE = 4',
    }
    for concept, text in samples.items():
        assert re.search(ONE_HOME[concept][0], text), concept
