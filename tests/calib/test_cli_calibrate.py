"""``matrix-tracker calibrate`` as a batch on the real MATRIX sample: guided by the records of
``matrix-tracker register`` (``--registration``), stale poses kept out of ``calibrations/`` unless
``--write-stale``, and no frame's failure ends the run."""

import csv
import json
import os
import shutil

import cv2
import numpy as np
import pytest

from matrix_core.calib.evaluation import pose_errors
from matrix_core.cli.main import main
from matrix_core.datasets import MatrixDataset, open_dataset

cv2.setNumThreads(1)


def _rows(out):
    with open(out / 'calibration_status.csv', newline='') as fh:
        return list(csv.DictReader(fh))


def _extrinsic(out, drone, frame):
    return out / 'calibrations' / 'extrinsic' / f'extr_Drone{drone}_{frame:04d}.xml'


@pytest.fixture(scope='module')
def registered(matrix_sample, tmp_path_factory):
    """``matrix-tracker register`` on every drone, first 2 frames of the real sample."""
    reg = tmp_path_factory.mktemp('reg')
    assert main(['register', str(matrix_sample), '--out', str(reg), '--max-frames', '2']) == 0
    return reg


def test_registration_guides_every_real_view(matrix_sample, registered, tmp_path, capsys):
    """8 drones x 2 frames, each guided by its registration: all ok and written, median within
    0.1 deg / 3 cm of the stored calibration (measured: 0.015 deg / 0.7 cm over all 40 views)."""
    out = tmp_path / 'calib'
    assert (
        main(
            [
                'calibrate',
                str(matrix_sample),
                '--out',
                str(out),
                '--registration',
                str(registered),
                '--max-frames',
                '2',
                '--compare',
            ]
        )
        == 0
    )
    printed = capsys.readouterr().out
    assert "16 images: {'ok': 16, 'stale': 0, 'failed': 0}; 0 raised" in printed, printed
    assert '16 guided by their registration' in printed
    rows = _rows(out)
    assert len(rows) == 16 and {r['view'] for r in rows} == {f'D{n}' for n in range(1, 9)}
    for r in rows:
        assert (r['status'], r['guide'], r['registration'], r['written'], r['failure']) == (
            'ok',
            'registration',
            'ok',
            'True',
            '',
        ), r
    # What was written is what the reader reads back, against the stored calibration.
    truth, written = MatrixDataset(matrix_sample), open_dataset(out)
    errors = np.array([pose_errors(written.camera(v, f), truth.camera(v, f)) for v in truth.views for f in (0, 1)])
    assert np.median(errors[:, 0]) < 0.1 and np.median(errors[:, 1]) < 0.03, np.median(errors, axis=0)
    assert np.allclose(errors, [[float(r['rot_err_deg']), float(r['centre_err_m'])] for r in rows], atol=1e-6)


def _shift_ground(record_path, dx_m):
    """Move the record's ground homography ``dx_m`` metres along the file world's x: a wrong registration."""
    record = json.loads(record_path.read_text())
    shift = np.array([[1.0, 0.0, dx_m], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    record['H_img_to_ground'] = (shift @ np.array(record['H_img_to_ground'])).tolist()
    record_path.write_text(json.dumps(record))


def test_stale_poses_are_written_only_when_asked(matrix_sample, registered, tmp_path):
    """D5: frame 0 has no record (calibrated from the image motion, as live without a registration);
    frame 1's record is 1.5 m off, so its pose disagrees with the registration and the frame is stale. Its
    last good pose goes into calibrations/ only with --write-stale; the CSV lists it stale either way."""
    reg = tmp_path / 'reg'
    shutil.copytree(registered, reg)
    (reg / 'registration' / 'Drone5_0000.json').unlink()
    _shift_ground(reg / 'registration' / 'Drone5_0001.json', 1.5)
    for flags, written in (([], False), (['--write-stale'], True)):
        out = tmp_path / f'calib{len(flags)}'
        assert (
            main(
                [
                    'calibrate',
                    str(matrix_sample),
                    '--out',
                    str(out),
                    '--registration',
                    str(reg),
                    '--views',
                    'D5',
                    '--max-frames',
                    '2',
                ]
                + flags
            )
            == 0
        )
        first, second = _rows(out)
        assert (first['status'], first['registration'], first['written']) == ('ok', 'missing', 'True'), first
        assert first['guide'] != 'registration'
        assert second['status'] == 'stale' and 'from the camera the registration implies' in second['message'], second
        assert second['written'] == str(written) and _extrinsic(out, 5, 1).is_file() == written
        assert _extrinsic(out, 5, 0).is_file()
        assert open_dataset(out).frames == ((0, 1) if written else (0,))
    # The stale file holds the last good pose (frame 0's).
    stale = open_dataset(tmp_path / 'calib1')
    rot, centre = pose_errors(stale.camera('D5', 1), stale.camera('D5', 0))
    assert rot < 1e-4 and centre < 1e-4  # the same pose, to the files' precision


def _sample_copy(matrix_sample, root):
    """The sample folder as symlinks, so that single images can be replaced."""
    shutil.copytree(matrix_sample, root, copy_function=os.symlink)
    return root


def test_a_bad_frame_fails_alone(matrix_sample, tmp_path, capsys):
    """D5 frame 1 is not a JPEG (cannot be read), frame 2 is half size (the calibration raises): both are
    failed with the step and reason, the others calibrate and the summary counts them."""
    data = _sample_copy(matrix_sample, tmp_path / 'data')
    images = data / 'image_subsets' / 'D5'
    (images / '0001.jpg').unlink()
    (images / '0001.jpg').write_bytes(b'\xff\xd8\xff\xe0 not a jpeg')
    small = cv2.resize(cv2.imread(str(matrix_sample / 'image_subsets' / 'D5' / '0002.jpg')), (960, 540))
    (images / '0002.jpg').unlink()
    cv2.imwrite(str(images / '0002.jpg'), small)
    out = tmp_path / 'calib'
    assert main(['calibrate', str(data), '--out', str(out), '--views', 'D5', '--max-frames', '4']) == 0
    printed = capsys.readouterr().out
    assert "4 images: {'ok': 2, 'stale': 0, 'failed': 2}; 2 raised" in printed, printed
    rows = _rows(out)
    assert [(r['status'], r['failure']) for r in rows] == [
        ('ok', ''),
        ('failed', 'read image'),
        ('failed', 'calibrate'),
        ('ok', ''),
    ]
    assert 'cannot decode image' in rows[1]['message'] and '0001.jpg' in rows[1]['message']
    assert 'intrinsics are for 1920x1080' in rows[2]['message']
    assert [_extrinsic(out, 5, f).is_file() for f in range(4)] == [True, False, False, True]


def test_registration_folder_without_records_is_an_error(matrix_sample, tmp_path, capsys):
    (tmp_path / 'reg').mkdir()  # beside the output: an output inside an input is refused for that alone
    assert (
        main(
            [
                'calibrate',
                str(matrix_sample),
                '--out',
                str(tmp_path / 'out'),
                '--registration',
                str(tmp_path / 'reg'),
                '--views',
                'D5',
                '--max-frames',
                '1',
            ]
        )
        == 2
    )
    assert 'no registration records' in capsys.readouterr().err
