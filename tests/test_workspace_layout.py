"""Every ROS package is a proper ament package that `colcon build` and `ros2 run` understand."""

import configparser
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / 'ros2_ws' / 'src'
REQUIRED = (
    'matrix_core',
    'matrix_ros',
    'matrix_calib',
    'matrix_register',
    'matrix_bev_tracker',
    'matrix_live_view',
    'matrix_msgs',
)
PYTHON_PACKAGES = [p for p in REQUIRED if p != 'matrix_msgs']


def test_all_packages_present():
    assert set(REQUIRED) <= {p.name for p in SRC.iterdir() if (p / 'package.xml').is_file()}


@pytest.mark.parametrize('name', PYTHON_PACKAGES)
def test_ament_python_package(name):
    pkg = SRC / name
    xml = ET.parse(pkg / 'package.xml').getroot()
    assert xml.findtext('name') == name
    assert xml.find('export/build_type').text == 'ament_python'
    cfg = configparser.ConfigParser()
    cfg.read(pkg / 'setup.cfg')
    assert cfg['develop']['script_dir'] == f'$base/lib/{name}'
    assert cfg['install']['install_scripts'] == f'$base/lib/{name}'
    assert (pkg / 'resource' / name).is_file() and (pkg / name / '__init__.py').is_file()


def test_built_install_tree(install_dir):
    for name in REQUIRED:
        assert (install_dir / name / 'share' / name / 'package.xml').exists(), f'{name} not installed'
    assert (install_dir / 'matrix_msgs' / 'share' / 'matrix_msgs' / 'msg' / 'HomographyStamped.msg').exists()


def test_interfaces_import_and_serialize():
    from rclpy.serialization import deserialize_message, serialize_message
    from matrix_msgs.msg import HomographyStamped, Track, TrackArray

    msg = HomographyStamped(
        confidence=0.5, inliers=10, matches=20, status=HomographyStamped.OK, reason='re-keyed', backend='sift'
    )
    msg.h_cur_to_ref = [1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0]
    back = deserialize_message(serialize_message(msg), HomographyStamped)
    assert list(back.h_cur_to_ref) == list(msg.h_cur_to_ref)
    assert (back.status, back.reason) == (HomographyStamped.OK, 're-keyed')
    tracks = TrackArray(tracks=[Track(id=4, score=0.9)])
    assert deserialize_message(serialize_message(tracks), TrackArray).tracks[0].id == 4
