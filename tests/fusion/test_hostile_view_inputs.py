"""Hostile inputs of one view of a live frame, as the fuse node hands them to
``fusion.view_inputs``: images of the wrong size, encoding or zero bytes; NaN, Inf, singular and absurdly
scaled homographies and CameraInfo. Each bad one makes that view missing with its reason (the node logs it
and publishes it in /diagnostics, tests/system/test_fuse_faults.py); an absurd scale of a homography, which
means nothing for a homography, changes nothing."""

import numpy as np
import pytest
from sensor_msgs.msg import CompressedImage, Image
from std_msgs.msg import Header

from matrix_core.bev.data import prepare_image
from matrix_core.datasets import MatrixDataset
from matrix_core.fusion.view_inputs import EARLY_KEPT, NOT_SENT, ImageNotSent, ViewInputs
from matrix_core.fusion.views import FrameStatus
from matrix_core.register.registration import Registration, RegistrationStatus
from matrix_ros.conversions import camera_to_camera_info, image_to_compressed, image_to_msg, registration_to_msg


@pytest.fixture(scope='module')
def real(matrix_sample):
    ds = MatrixDataset(matrix_sample)
    camera, image = ds.camera('D1', 0), ds.load_image('D1', 0)
    return camera, image


def _inputs():
    return ViewInputs((480, 272), min_confidence=0.3, reduced_decode=True)


def _homography(camera, scale=1.0, values=None):
    msg = registration_to_msg(
        Registration(RegistrationStatus.OK, np.eye(3), np.linalg.inv(camera.img_H_ground()), confidence=0.9)
    )
    h = np.array(msg.h_img_to_ground) * scale if values is None else np.asarray(values, float).ravel()
    msg.h_img_to_ground = h.tolist()
    return msg


def _camera_info(camera, **changes):
    msg = camera_to_camera_info(camera)
    for k, v in changes.items():
        setattr(msg, k, v)
    return msg


def test_good_view_is_usable(real):
    camera, image = real
    for geometry, kind in ((_homography(camera), 'homography'), (_camera_info(camera), 'camera_info')):
        view = _inputs().view_input('D1', image_to_compressed(image), geometry, kind)
        assert view.usable, view.reason


def test_an_image_its_drone_did_not_send_makes_the_view_missing_saying_so(real):
    # link_sender's notice stands in for the image (the frame does not wait for it); with or without geometry
    camera, _ = real
    for geometry in (_homography(camera), None):
        view = _inputs().view_input('D1', ImageNotSent(Header()), geometry, 'homography')
        assert not view.usable and view.reason == NOT_SENT and view.status == FrameStatus.MISSING


def test_a_frame_of_geometry_without_any_image_gives_no_views(real):
    # geometry_qos history replayed after a restart: nothing to see, so the node fuses nothing
    camera, image = real
    inputs, geometry = _inputs(), _homography(camera)
    assert inputs.frame_views({'D1/geometry': geometry, 'D2/geometry': geometry}, ['D1', 'D2'], 'homography') is None
    views = inputs.frame_views(
        {'D1/geometry': geometry, 'D1/image': image_to_compressed(image), 'D2/geometry': geometry},
        ['D1', 'D2'],
        'homography',
    )
    assert views['D1'].usable and views['D2'].reason == 'no image'


@pytest.mark.parametrize(
    'make, reason',
    [
        (lambda img: image_to_compressed(img[::3, ::3].copy()), 'image is 640x360, its camera_info is for 1920x1080'),
        (lambda img: image_to_msg(img[:540, :960].copy()), 'image is 960x540, its camera_info is for 1920x1080'),
        (lambda img: CompressedImage(format='jpeg'), 'empty'),
        (lambda img: CompressedImage(format='jpeg', data=b'\xff\xd8 not a jpeg'), 'corrupt'),
        (
            lambda img: Image(height=4, width=4, encoding='yuv422_weird', step=8, data=bytes(32)),
            'unsupported image encoding',
        ),
        (lambda img: Image(height=4, width=4, encoding='bgr8', step=12, data=bytes(0)), 'too short'),
    ],
    ids=['wrong size jpeg', 'wrong size raw', 'zero bytes', 'corrupt jpeg', 'encoding', 'truncated raw'],
)
def test_bad_images_make_the_view_missing(real, make, reason):
    camera, image = real
    view = _inputs().view_input('D1', make(image), _camera_info(camera), 'camera_info')
    assert not view.usable and reason in view.reason, view.reason


@pytest.mark.parametrize(
    'values, reason',
    [
        (np.full(9, np.nan), 'NaN'),
        (np.r_[np.inf, np.ones(8)], 'NaN/infinite'),
        (np.zeros(9), 'singular'),
        ([1, 2, 3, 2, 4, 6, 0, 0, 1], 'singular'),
        (np.ones(4), '9 values'),
    ],
    ids=['nan', 'inf', 'zeros', 'rank 2', 'wrong length'],
)
def test_bad_homographies_make_the_view_missing(real, values, reason):
    camera, image = real
    view = _inputs().view_input('D1', image_to_compressed(image), _homography(camera, values=values), 'homography')
    assert not view.usable and reason in view.reason, view.reason


@pytest.mark.parametrize('scale', [1e-12, -1.0, 1e12])
def test_a_homography_at_any_scale_is_the_same_homography(real, scale):
    camera, image = real
    good = _inputs().view_input('D1', image_to_compressed(image), _homography(camera), 'homography')
    scaled = _inputs().view_input('D1', image_to_compressed(image), _homography(camera, scale), 'homography')
    assert scaled.usable, scaled.reason
    norm = lambda H: H / H[2, 2]
    np.testing.assert_allclose(norm(scaled.img_H_ground), norm(good.img_H_ground), rtol=1e-9)


@pytest.mark.parametrize(
    'changes, reason',
    [
        ({'p': [float('nan')] * 12}, 'NaN'),
        ({'p': [float('inf')] + [0.0] * 11}, 'NaN'),
        ({'k': [0.0] * 9}, 'singular'),
        ({'width': 0, 'height': 0}, 'empty'),
    ],
    ids=['nan p', 'inf p', 'singular k', 'no size'],
)
def test_bad_camera_info_makes_the_view_missing(real, changes, reason):
    camera, image = real
    view = _inputs().view_input('D1', image_to_compressed(image), _camera_info(camera, **changes), 'camera_info')
    assert not view.usable and reason.lower() in view.reason.lower(), view.reason


def test_an_absurdly_scaled_camera_info_is_refused(real):
    """``p`` scaled by 1e6 is no longer ``K [R | t]`` with a rotation: refused, not reinterpreted."""
    camera, image = real
    msg = _camera_info(camera)
    msg = _camera_info(camera, p=[1e6 * v for v in msg.p])
    view = _inputs().view_input('D1', image_to_compressed(image), msg, 'camera_info')
    assert not view.usable and 'rotation' in view.reason, view.reason


def test_an_image_decoded_on_arrival_gives_the_same_view(real):
    # the fuse node decodes each image as it arrives (decode_early); the frame's view must not change by it
    camera, image = real
    msg, geometry = image_to_compressed(image), _homography(camera)
    plain, early = _inputs(), _inputs()
    for inputs in (plain, early):  # a first frame teaches the full size: the next decodes reduced
        assert inputs.view_input('D1', image_to_compressed(image), geometry, 'homography').usable
    early.decode_early('D1', msg)
    assert len(early._early) == 1
    a, b = plain.view_input('D1', msg, geometry, 'homography'), early.view_input('D1', msg, geometry, 'homography')
    assert b.usable and not early._early  # taken from the early decode, then forgotten
    np.testing.assert_array_equal(a.image, b.image)
    np.testing.assert_allclose(a.img_H_ground, b.img_H_ground)
    assert a.image.shape[:2] == (540, 960)  # decoded at 1/2 for a 480x272 network input
    # the network input made on arrival too: what the fuser would make of the same image, exactly
    assert a.network_image is None
    np.testing.assert_array_equal(b.network_image, prepare_image(a.image, (480, 272)))


def test_a_views_first_jpeg_is_decoded_in_full_the_next_ones_reduced(real, monkeypatch):
    # the first in full, as the offline evaluation decodes every frame (the tracks start from it: live == offline)
    from matrix_core.fusion import view_inputs

    camera, image = real
    reductions = []
    decode = view_inputs.image_from_msg
    monkeypatch.setattr(view_inputs, 'image_from_msg', lambda msg, r=1: reductions.append(r) or decode(msg, r))
    inputs, geometry = _inputs(), _camera_info(camera)
    view = inputs.view_input('D1', image_to_compressed(image), geometry, 'camera_info')
    assert view.usable and view.image.shape[:2] == (1080, 1920) and reductions == [1]
    view = inputs.view_input('D1', image_to_compressed(image), geometry, 'camera_info')
    assert view.usable and view.image.shape[:2] == (540, 960) and reductions == [1, 2]
    # the stream's size changes: the reduced decode shows it, a full decode learns it, the size check says so
    view = inputs.view_input('D1', image_to_compressed(image[::2, ::2].copy()), geometry, 'camera_info')
    assert reductions == [1, 2, 2, 1] and inputs.full_size['D1'] == (960, 540)
    assert not view.usable and 'image is 960x540, its camera_info is for 1920x1080' in view.reason, view.reason
    # the size check is each image's own: the next frame's image, decoded on arrival, does not change it
    msg = image_to_compressed(image)
    inputs.decode_early('D1', msg)
    inputs.decode_early('D1', image_to_compressed(image[::2, ::2].copy()))
    view = inputs.view_input('D1', msg, geometry, 'camera_info')
    assert view.usable and view.image.shape[:2] == (1080, 1920), view.reason


def test_early_decodes_are_bounded_and_a_bad_image_still_says_why(real):
    camera, image = real
    inputs, geometry = _inputs(), _homography(camera)
    bad = image_to_compressed(image)
    bad.data = bytes(100)
    inputs.decode_early('D1', bad)  # not decodable: left for view_input, which names the problem
    view = inputs.view_input('D1', bad, geometry, 'homography')
    assert not view.usable and view.reason
    small = image_to_compressed(image[::8, ::8].copy())
    for _ in range(EARLY_KEPT + 5):  # images of frames never fused (late, superseded) do not pile up
        inputs.decode_early('D1', image_to_compressed(image[::8, ::8].copy()))
    inputs.decode_early('D1', small)
    assert len(inputs._early) == EARLY_KEPT and id(small) in inputs._early


def test_images_deferred_while_an_earlier_frame_waits_are_decoded_after_it(real):
    # fuse does not decode a later frame's images while an earlier frame waits for its registrations (they would
    # take the cores from them); it decodes them once a frame was fused, and a frame fused first decodes its own
    camera, image = real
    inputs, geometry = _inputs(), _homography(camera)
    assert inputs.view_input('D1', image_to_compressed(image), geometry, 'homography').usable  # learns the size
    first, second = image_to_compressed(image), image_to_compressed(image)
    inputs.decode_early('D1', first, defer=True)
    inputs.decode_early('D2', second, defer=True)
    assert not inputs._early and len(inputs._deferred) == 2  # nothing decoded yet
    view = inputs.view_input('D1', first, geometry, 'homography')  # its frame came before the deferred decode
    assert view.usable and view.network_image is None and len(inputs._deferred) == 1
    inputs.decode_deferred()
    assert not inputs._deferred and list(inputs._early) == [id(second)]  # only the one not used yet
    view = inputs.view_input('D2', second, geometry, 'homography')
    assert view.usable and view.network_image is not None and not inputs._early
