"""Malformed MATRIX folders, on a copy of the real sample: missing files, bad XML and JSON, wrong
numbering. Each is a :class:`DatasetError` naming the file and what is wrong, or a frame left out with the
reason (``incomplete_frames``); never a crash from inside OpenCV or json, never a silent wrong answer."""

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from matrix_core.datasets import open_dataset
from matrix_core.datasets.types import DatasetError


@pytest.fixture
def sample(matrix_sample, tmp_path):
    """The real sample as per-file symlinks (nothing copied); a test unlinks what it damages."""
    return shutil.copytree(matrix_sample, tmp_path / 'sample', copy_function=os.symlink)


def _replace(path, text):
    path.unlink()
    path.write_text(text)


@pytest.mark.parametrize(
    'content',
    ['', '<?xml version="1.0"?>\n<opencv_storage>\n<rvec type_id="opencv-matrix"><rows>3'],
    ids=['empty', 'truncated'],
)
def test_bad_calibration_xml(sample, content):
    _replace(sample / 'calibrations/extrinsic/extr_Drone3_0001.xml', content)
    ds = open_dataset(sample)
    with pytest.raises(DatasetError, match=r'cannot parse calibration file .*extr_Drone3_0001\.xml'):
        ds.camera('D3', 1)
    assert ds.camera('D3', 2) is not None  # the other files still read


def test_nan_in_a_calibration_file(sample):
    from matrix_core.datasets.opencv_xml import write_matrices

    path = sample / 'calibrations/extrinsic/extr_Drone3_0001.xml'
    path.unlink()
    write_matrices(path, {'rvec': [np.nan, 0.0, 0.0], 'tvec': [0.0, 0.0, 1.0]})
    with pytest.raises(DatasetError, match=r'extr_Drone3_0001\.xml: node <rvec> is empty or not finite'):
        open_dataset(sample).camera('D3', 1)


def test_bad_annotation_and_meta_json(sample):
    _replace(sample / 'annotations_positions/0002.json', '[{"personID": 1, "views": [')
    ds = open_dataset(sample)
    with pytest.raises(DatasetError, match=r'malformed annotation file .*0002\.json'):
        ds.annotations(2)
    assert ds.annotations(1)
    (sample / 'matrix_tracker_meta.json').write_text('{"area_file_xy": [0, ')
    with pytest.raises(DatasetError, match=r'malformed .*matrix_tracker_meta\.json'):
        open_dataset(sample)
    run = subprocess.run(
        [sys.executable, '-m', 'matrix_core.cli.main', 'info', str(sample)], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 2 and 'matrix_tracker_meta.json' in run.stderr and 'Traceback' not in run.stderr


def test_wrong_numbering_is_named(sample):
    os.rename(sample / 'image_subsets/D3/0002.jpg', sample / 'image_subsets/D3/2.jpg')
    with pytest.raises(
        DatasetError,
        match=r'image_subsets/D3: image files must be named by their frame as TTTT.*'
        r'misnamed: 2\.jpg',
    ):
        open_dataset(sample).frames


def test_missing_files_leave_the_frame_out_and_say_why(sample):
    (sample / 'image_subsets/D4/0001.jpg').unlink()
    (sample / 'calibrations/intrinsic/intr_Drone7_0003.xml').unlink()
    ds = open_dataset(sample)
    assert ds.frames == (0, 2, 4)
    assert ds.incomplete_frames == {1: 'no D4 image', 3: 'no D7 calibration'}
    (sample / 'calibrations/extrinsic/extr_Drone2_0000.xml').unlink()  # intrinsic there, extrinsic not
    with pytest.raises(DatasetError, match=r'calibration file not found: .*extr_Drone2_0000\.xml'):
        ds.camera('D2', 0)
