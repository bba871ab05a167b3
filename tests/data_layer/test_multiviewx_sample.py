"""The MultiviewX reader on real MultiviewX files (../shared/multiviewx_sample, see its README)."""

import json

import cv2
import numpy as np
import pytest

from matrix_core.cli.main import main
from matrix_core.datasets import MultiviewXDataset, open_dataset
from matrix_core.datasets.opencv_xml import read_matrices
from matrix_core.experiments.table3 import foot_point_agreement


@pytest.fixture(scope='module')
def sample(shared_dir):
    path = shared_dir / 'multiviewx_sample'
    if not path.is_dir():
        pytest.fail(f'real MultiviewX sample {path} is missing')
    return path


def test_annotated_positions_project_onto_the_annotated_feet(sample):
    ds = open_dataset(sample)
    assert isinstance(ds, MultiviewXDataset)
    assert ds.views == ('C1', 'C2', 'C3', 'C4', 'C5', 'C6') and ds.annotated_frames == tuple(range(1, 11))
    agreement = foot_point_agreement(sample)  # the measurement the experiments' Table III step reports
    assert agreement['format'] == 'MultiviewXDataset' and set(agreement['views']) == set(ds.views)
    for view, a in agreement['views'].items():
        assert a['n'] > 150 and a['median_px'] <= 8.0, f'{view}: median {a["median_px"]:.1f} px'
        assert a['p90_px'] < 25.0 and a['behind_camera'] == 0, (view, a)


def test_reader_cameras_reproduce_raw_opencv_with_positive_depth(sample):
    # The files' own projection (raw cv2.projectPoints of file-world metres (pos % 1000, pos // 1000) / 40)
    # is reproduced exactly, with the points in front of the camera (the files put them at negative depth).
    ds = MultiviewXDataset(sample)
    for i, view in enumerate(ds.views, start=1):
        persons = [p for p in ds.annotations(1) if view in p.boxes]
        pos = np.array([p.position_id for p in persons])
        file_world = np.c_[pos % 1000, pos // 1000, np.zeros(len(pos))] / 40.0
        intr = read_matrices(
            sample / f'calibrations/intrinsic/intr_Camera{i}.xml', ['camera_matrix', 'distortion_coefficients']
        )
        extr = read_matrices(sample / f'calibrations/extrinsic/extr_Camera{i}.xml', ['rvec', 'tvec'])
        raw = cv2.projectPoints(
            file_world.reshape(-1, 1, 3),
            extr['rvec'],
            extr['tvec'],
            intr['camera_matrix'],
            intr['distortion_coefficients'],
        )[0].reshape(-1, 2)
        cam = ds.camera(view, 0)
        world = np.c_[[p.world_xy for p in persons], np.zeros(len(persons))]
        assert len(persons) > 10 and np.all(cam.depth(world) > 0)  # everyone it sees is in front of it
        np.testing.assert_allclose(cam.project(world), raw, atol=1e-6)
        assert cam.center[2] == pytest.approx(2.5, abs=0.01) and 8.0 < cam.tilt_deg < 12.0  # README: 10 deg down


def test_area_and_info_follow_the_dataset_parameters(sample, capsys):
    # MultiviewX's own parameters: 25 m along x, 16 m along y (internal y is the file's negated).
    ds = MultiviewXDataset(sample)
    x0, y0, x1, y1 = ds.area
    assert (x0, y0, x1, y1) == (0.0, -16.0, 25.0, 0.0) and (x1 - x0, y1 - y0) == (25.0, 16.0)
    for frame in ds.annotated_frames:
        for person in ds.annotations(frame):
            assert x0 <= person.world_xy[0] <= x1 and y0 <= person.world_xy[1] <= y1
    assert main(['info', str(sample), '--json']) == 0
    info = json.loads(capsys.readouterr().out)
    assert info['format'] == 'multiviewx' and info['area_m'] == [0.0, -16.0, 25.0, 0.0]
    assert info['views'] == ['C1', 'C2', 'C3', 'C4', 'C5', 'C6'] and info['annotated_frames'] == 10
    assert info['camera_height_m'] == '2.50 .. 2.50'
    low, high = map(float, info['camera_tilt_below_horizon_deg'].split(' .. '))
    assert 8.0 < low <= high < 12.0
