"""A JPEG cut to half its bytes decodes without an error (libjpeg fills the rest with grey): it is a bad image
everywhere. The readers refuse it, ``evaluate`` masks that view with the reason, the live decoders
(fuse's view inputs, the drones' grey decode) drop it saying why, ``bag`` and ``bag --compressed`` stop
naming it and leave no bag, so nothing re-encodes the damage into a valid JPEG."""

import json
import os
import shutil
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from matrix_core.cli.main import main
from matrix_core.datasets import DatasetError, MatrixDataset
from matrix_core.encoded_images import CorruptImage, check_complete
from matrix_core.fusion.settings import shipped_checkpoint
from matrix_core.fusion.view_inputs import ViewInputs
from matrix_core.message_fields import ConversionError, gray_image_from_msg, image_from_msg


def cut_in_half(path):
    data = path.read_bytes()
    path.unlink()  # a linked copy: the link goes, the shared sample stays
    path.write_bytes(data[: len(data) // 2])
    return data


def linked_copy(src, dst):
    shutil.copytree(src, dst, copy_function=os.symlink)
    return dst


def test_a_half_jpeg_is_refused_by_the_readers(matrix_sample, tmp_path):
    whole = (matrix_sample / 'image_subsets/D3/0001.jpg').read_bytes()
    half = whole[: len(whole) // 2]
    (tmp_path / 'half.jpg').write_bytes(half)
    assert cv2.imread(str(tmp_path / 'half.jpg')) is not None  # what fooled the readers: grey rows, no error
    check_complete(whole)
    with pytest.raises(CorruptImage, match='truncated JPEG'):
        check_complete(half)
    ok, png = cv2.imencode('.png', cv2.imdecode(np.frombuffer(whole, np.uint8), cv2.IMREAD_COLOR)[:64, :64])
    with pytest.raises(CorruptImage, match='truncated PNG'):
        check_complete(png.tobytes()[: len(png) // 2])
    data = linked_copy(matrix_sample, tmp_path / 'sample')
    cut_in_half(data / 'image_subsets/D3/0001.jpg')
    with pytest.raises(DatasetError, match=r'cannot decode image .*0001\.jpg: truncated JPEG'):
        MatrixDataset(data).load_image('D3', 1)


def test_the_live_decoders_drop_a_half_jpeg(matrix_sample):
    whole = (matrix_sample / 'image_subsets/D3/0001.jpg').read_bytes()
    msg = SimpleNamespace(format='jpeg', data=whole[: len(whole) // 2])
    for decode in (image_from_msg, gray_image_from_msg, lambda m: image_from_msg(m, 4)):
        with pytest.raises(ConversionError, match='truncated JPEG'):
            decode(msg)
    dataset = MatrixDataset(matrix_sample)
    from matrix_ros.conversions import registration_to_msg  # fuse's geometry message of the view

    from matrix_core.register.registration import Registration, RegistrationStatus

    camera = dataset.camera('D3', 1)
    geometry = registration_to_msg(
        Registration(RegistrationStatus.OK, np.eye(3), np.linalg.inv(camera.img_H_ground()), confidence=0.9)
    )
    view = ViewInputs((480, 272), min_confidence=0.3, reduced_decode=True).view_input('D3', msg, geometry, 'homography')
    assert not view.usable and 'truncated JPEG' in view.reason


@pytest.mark.parametrize('compressed', [False, True], ids=['raw', 'compressed'])
def test_bag_stops_at_a_half_jpeg_and_leaves_no_bag(matrix_sample, tmp_path, capsys, compressed):
    data = linked_copy(matrix_sample, tmp_path / 'sample')
    cut_in_half(data / 'image_subsets/D3/0001.jpg')
    out = tmp_path / 'bag'
    assert main(['bag', str(data), '--out', str(out), *(['--compressed'] if compressed else [])]) == 2
    err = capsys.readouterr().err
    assert 'D3/0001.jpg: truncated JPEG' in err and 'Traceback' not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ['sample']  # no bag, no partial folder
    assert main(['bag', str(out)]) == 2  # nothing to list or replay


@pytest.mark.slow
def test_evaluate_masks_a_half_jpeg(matrix_sample, tmp_path, capsys):
    data = linked_copy(matrix_sample, tmp_path / 'sample')
    cut_in_half(data / 'image_subsets/D3/0001.jpg')
    out = tmp_path / 'eval'
    assert (
        main(['evaluate', str(data), '--checkpoint', str(shipped_checkpoint()), '--out', str(out), '--heatmaps', '1'])
        == 0
    )
    failures = json.loads((out / 'metrics.json').read_text())['failures']
    assert failures['views_masked'] == 1 and failures['frames_failed'] == 0, failures
    (masked,) = failures['masked_views']
    assert (masked['view'], masked['frame']) == ('D3', 1) and 'truncated JPEG' in masked['reason']
    assert 'D3 frame 1: image:' in capsys.readouterr().out
