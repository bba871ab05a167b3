"""``matrix-tracker evaluate`` on a damaged copy of the real MATRIX sample: no frame ends the run. A view whose
image or calibration cannot be used is masked in that frame, a frame that cannot run is not scored, and both
are printed and listed in ``metrics.json`` with their reasons."""

import json
import os
import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from matrix_core.bev.inference import SequenceRunner
from matrix_core.cli.main import main
from matrix_core.datasets import open_dataset
from matrix_core.fusion.settings import shipped_checkpoint
from matrix_core.register.file_frame import record_name, registration_to_record
from matrix_core.register.registration import Registration, RegistrationStatus

CHECKPOINT = shipped_checkpoint()
pytestmark = pytest.mark.slow


def linked_copy(src: Path, dst: Path) -> Path:
    """``src`` as a tree of per-file symlinks (98 MB not copied); a damaged file is unlinked and rewritten."""
    shutil.copytree(src, dst, copy_function=os.symlink)
    return dst


def replace(path: Path, data: bytes) -> None:
    path.unlink()
    path.write_bytes(data)


def _evaluate(dataset, out, *extra):
    return main(
        ['evaluate', str(dataset), '--checkpoint', str(CHECKPOINT), '--out', str(out), '--heatmaps', '1', *extra]
    )


def test_damaged_frames_and_views_are_reported_and_the_run_finishes(matrix_sample, tmp_path, capsys, monkeypatch):
    data = linked_copy(matrix_sample, tmp_path / 'sample')
    images, calib = data / 'image_subsets', data / 'calibrations'
    replace(images / 'D2' / '0001.jpg', b'')  # zero bytes
    replace(images / 'D3' / '0002.jpg', b'\xff\xd8 not a jpeg at all' * 50)  # corrupt
    small = cv2.resize(cv2.imread(str(matrix_sample / 'image_subsets/D4/0003.jpg')), (960, 540))
    (images / 'D4' / '0003.jpg').unlink()
    cv2.imwrite(str(images / 'D4' / '0003.jpg'), small)  # wrong size
    (calib / 'extrinsic' / 'extr_Drone5_0001.xml').unlink()  # a view's calibration missing
    text = (matrix_sample / 'calibrations/extrinsic/extr_Drone6_0002.xml').read_bytes()
    replace(calib / 'extrinsic' / 'extr_Drone6_0002.xml', text[: len(text) // 2])  # truncated XML
    replace(data / 'matchings' / 'Pedestrians' / '3d_0003.txt', b'1 2 three\n')  # ground truth unreadable
    (calib / 'intrinsic' / 'intr_Drone7_0004.xml').unlink()  # frame 4 incomplete

    step = SequenceRunner.step

    def failing_step(self, frame, *args):  # the model (decoding) raising in one frame
        if frame == 1:
            raise RuntimeError('injected decode failure')
        return step(self, frame, *args)

    monkeypatch.setattr(SequenceRunner, 'step', failing_step)

    out = tmp_path / 'eval'
    assert _evaluate(data, out) == 0
    printed = capsys.readouterr().out
    failures = json.loads((out / 'metrics.json').read_text())['failures']
    failed = {f['frame']: f['reason'] for f in failures['failed_frames']}
    masked = {(m['view'], m['frame']): m['reason'] for m in failures['masked_views']}
    assert (failures['frames_failed'], failures['frames_scored'], failures['views_masked']) == (3, 2, 5), failures
    assert failed[1] == 'inference: RuntimeError: injected decode failure'
    assert failed[3].startswith('ground truth: DatasetError: malformed table') and '3d_0003.txt' in failed[3]
    assert failed[4] == 'dataset: no D7 calibration'
    assert set(masked) == {('D2', 1), ('D5', 1), ('D3', 2), ('D6', 2), ('D4', 3)}
    assert masked[('D2', 1)].startswith('image: DatasetError: cannot decode image') and '0001.jpg' in masked[('D2', 1)]
    assert masked[('D3', 2)].startswith('image: DatasetError: cannot decode image')
    assert 'is 960x540, its calibration is for 1920x1080' in masked[('D4', 3)]
    assert masked[('D5', 1)].startswith('calibration: DatasetError: calibration file not found')
    assert masked[('D6', 2)].startswith('calibration: DatasetError: cannot parse calibration file')
    assert '3 frame(s) failed (not scored: metrics over 2 frames), 5 view(s) masked:' in printed
    assert "frame 4: dataset: no D7 calibration" in printed and 'D4 frame 3: image:' in printed
    # the two intact frames are scored as usual (the model finds the people of the real sample)
    metrics = json.loads((out / 'metrics.json').read_text())['detection']
    assert metrics['recall'] > 0.8, metrics
    gt = np.loadtxt(out / 'ground_truth.txt', ndmin=2)
    assert set(gt[:, 0].astype(int)) == {0, 2}
    tracks = np.loadtxt(out / 'tracks.txt', ndmin=2)
    assert set(tracks[:, 0].astype(int)) <= {0, 2}
    assert (out / 'boxes_2d.txt').is_file() and (out / 'trajectories.png').is_file()


def _record(camera, ok=True) -> dict:
    """A registration record whose ground homography is that of ``camera`` (what a perfect register writes)."""
    return registration_to_record(
        Registration(
            RegistrationStatus.OK,
            np.eye(3),
            np.linalg.inv(camera.img_H_ground()),
            confidence=1.0,
            matches=100,
            inliers=100,
        )
    )


def test_broken_registration_records_mask_their_view(matrix_sample, tmp_path, capsys):
    """``--calibration registration`` with a NaN, a singular and an unparsable record: those views are masked
    with the reason, the others (records from the ground truth) evaluated."""
    dataset = open_dataset(matrix_sample)
    reg = tmp_path / 'reg' / 'registration'
    reg.mkdir(parents=True)
    for v in dataset.views:
        for f in dataset.frames:
            (reg / record_name(v, f)).write_text(json.dumps(_record(dataset.camera(v, f))))
    nan = json.loads((reg / record_name('D1', 0)).read_text())
    nan['H_img_to_ground'][0][0] = float('nan')
    (reg / record_name('D1', 0)).write_text(json.dumps(nan))
    singular = json.loads((reg / record_name('D2', 1)).read_text())
    singular['H_img_to_ground'] = [[1, 2, 3], [2, 4, 6], [0, 0, 1]]
    (reg / record_name('D2', 1)).write_text(json.dumps(singular))
    (reg / record_name('D3', 2)).write_text('{"status": "ok", "H_img_to')

    out = tmp_path / 'eval'
    assert (
        _evaluate(matrix_sample, out, '--calibration', 'registration', '--calibration-dir', str(tmp_path / 'reg')) == 0
    )
    failures = json.loads((out / 'metrics.json').read_text())['failures']
    masked = {(m['view'], m['frame']): m['reason'] for m in failures['masked_views']}
    assert (failures['frames_failed'], failures['frames_scored']) == (0, 5)
    assert set(masked) == {('D1', 0), ('D2', 1), ('D3', 2)}, masked
    assert 'H_img_to_ground has NaN/infinite values' in masked[('D1', 0)]
    assert 'H_img_to_ground is singular' in masked[('D2', 1)]
    assert 'unreadable record' in masked[('D3', 2)]
    assert json.loads((out / 'metrics.json').read_text())['detection']['recall'] > 0.8
