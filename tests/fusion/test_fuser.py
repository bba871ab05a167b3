"""Live fusion core on a real simulated sequence: frame by frame it must give exactly what the offline
evaluation (BevFrames + run_frames + BevTracker) gives on the same frames, and survive bad views."""

from pathlib import Path

import numpy as np
import pytest
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.data import BevFrames
from matrix_core.bev.evaluation import evaluate
from matrix_core.cli.main import main as cli
from matrix_core.datasets import open_dataset
from matrix_core.fusion.fuser import BevFuser
from matrix_core.fusion.settings import FuseSettings, shipped_checkpoint
from matrix_core.fusion.views import ViewInput, at_reduced_resolution, jpeg_reduction
from matrix_core.register.registration import Registration, RegistrationError, RegistrationStatus

torch.set_num_threads(1)
FRAMES = 4


@pytest.fixture(scope='module')
def sequence(tmp_path_factory):
    out = tmp_path_factory.mktemp('fusion') / 'sim'
    assert (
        cli(
            [
                'simulate',
                '--config',
                'complex',
                '--frames',
                str(FRAMES),
                '--seed',
                '11',
                '--fast',
                '--image_ext',
                '.png',
                '--out',
                str(out),
            ]
        )
        == 0
    )
    return out


@pytest.fixture(scope='module')
def model():
    return load_model(shipped_checkpoint())


def _offline(sequence, model, views=None):
    net, bev = model
    data = BevFrames(sequence, bev, calibration='ground_truth', views=views, cache_images=False)
    return evaluate(net, data, FuseSettings().tracker_settings(), progress=False)


def _live(sequence, model, make_view, settings=None):
    net, bev = model
    dataset = open_dataset(sequence)
    fuser = BevFuser(settings or FuseSettings(area=list(dataset.area)), net, bev)
    results = []
    for k, frame in enumerate(dataset.frames):
        views = {v: make_view(dataset, v, frame) for v in dataset.views}
        results.append(fuser.process(1.0 + 0.5 * k, {v: x for v, x in views.items() if x is not None}))
        fuser.prepare_next()  # as the fuse node, once a frame is published (offline, run_frames computes it later)
    return results


def _from_camera_info(dataset, view, frame):
    return ViewInput(dataset.load_image(view, frame), dataset.camera(view, frame).img_H_ground())


def _by_position(xy):
    return np.lexsort((np.round(xy[:, 1], 2), np.round(xy[:, 0], 2)))


def _assert_same(offline, live, atol):
    for k, r in enumerate(live):
        frame = offline.outputs[k].frame
        off = offline.outputs[k].detections
        # peaks of equal score may come in either order: compare them sorted by position
        a, b = _by_position(r.detections.xy), _by_position(off.xy)
        np.testing.assert_allclose(r.detections.xy[a], off.xy[b], atol=atol)
        np.testing.assert_allclose(r.detections.scores[a], off.scores[b], atol=atol)
        np.testing.assert_allclose(r.heatmap, offline.outputs[k].heatmap, atol=atol)
        sel = offline.tracks.frames == frame
        assert [t.track_id for t in r.tracks] == list(offline.tracks.ids[sel])
        np.testing.assert_allclose(np.reshape([t.xy for t in r.tracks], (-1, 2)), offline.tracks.xy[sel], atol=atol)


def test_camera_info_input_equals_offline(sequence, model):
    offline = _offline(sequence, model)
    live = _live(sequence, model, _from_camera_info)
    assert sum(len(r.detections) for r in live) > 10 * FRAMES  # a crowd of 40 is detected
    assert any(r.tracks for r in live)
    _assert_same(offline, live, 1e-5)
    assert all(r.available_views == [f'D{i}' for i in range(1, 9)] for r in live)
    assert live[-1].tracks[0].age >= 1 and set(live[0].timing) >= {'prepare_s', 'network_s', 'total_s'}


def test_registration_input_equals_offline(sequence, model):
    """A HomographyStamped's h_img_to_ground (pixels -> ground, normalised [2][2] = 1) gives the same result."""

    def from_registration(dataset, view, frame):
        H = np.linalg.inv(dataset.camera(view, frame).img_H_ground())
        return ViewInput(
            dataset.load_image(view, frame),
            Registration(RegistrationStatus.OK, None, H / H[2, 2]).img_H_ground,
            confidence=0.9,
        )

    _assert_same(_offline(sequence, model), _live(sequence, model, from_registration), 1e-4)


def test_missing_views_equal_offline_drop(sequence, model):
    """Views that never arrive are masked exactly like `evaluate --drop-views D2 D6`."""
    keep = ['D1', 'D3', 'D4', 'D5', 'D7', 'D8']
    offline = _offline(sequence, model, views=keep)
    live = _live(sequence, model, lambda d, v, f: _from_camera_info(d, v, f) if v in keep else None)
    _assert_same(offline, live, 1e-5)
    assert live[0].views['D2'].reason == 'no message' and live[0].available_views == keep


def test_bad_views_are_reported_not_used(sequence, model):
    net, bev = model
    dataset = open_dataset(sequence)
    frame = dataset.frames[0]
    fuser = BevFuser(FuseSettings(area=list(dataset.area)), net, bev)
    views = {v: _from_camera_info(dataset, v, frame) for v in dataset.views}
    views['D1'] = ViewInput(np.zeros((0, 5, 3), np.uint8), views['D1'].img_H_ground)
    views['D2'] = ViewInput(views['D2'].image, np.full((3, 3), np.nan))
    views['D3'] = ViewInput(None, None, 'corrupt compressed image')
    r = fuser.process(1.0, views)
    assert r.views['D3'].reason == 'corrupt compressed image'
    assert 'image' in r.views['D1'].reason and 'homography' in r.views['D2'].reason
    assert r.available_views == ['D4', 'D5', 'D6', 'D7', 'D8'] and len(r.detections) > 0
    with pytest.raises(RegistrationError, match='NaN'):
        Registration(RegistrationStatus.OK, None, [np.nan] * 9).img_H_ground
    with pytest.raises(RegistrationError, match='singular'):
        Registration(RegistrationStatus.OK, None, [0.0] * 9).img_H_ground
    # no usable view: no network run, no invented detections, the stream goes on
    empty = fuser.process(1.5, {})
    assert empty.heatmap is None and len(empty.detections) == 0 and 'temporal' in empty.resets


def test_gaps_reset_state(sequence, model):
    net, bev = model
    dataset = open_dataset(sequence)
    fuser = BevFuser(FuseSettings(area=list(dataset.area)), net, bev)
    views = {v: _from_camera_info(dataset, v, dataset.frames[0]) for v in dataset.views}
    assert fuser.process(1.0, views).resets == []
    assert fuser.process(1.5, views).resets == []
    assert fuser.process(2.5, views).resets == ['temporal']  # one frame lost
    assert fuser.process(20.0, views).resets == ['temporal', 'tracker']  # a new sequence
    assert fuser.process(3.0, views).resets == ['temporal', 'tracker']  # time went back (bag restarted)


def test_a_failed_prepare_next_restarts_the_temporal_state_and_says_so(sequence, model, monkeypatch):
    net, bev = model
    dataset = open_dataset(sequence)
    fuser = BevFuser(FuseSettings(area=list(dataset.area)), net, bev)
    views = {v: _from_camera_info(dataset, v, dataset.frames[0]) for v in dataset.views}
    fuser.process(1.0, views)

    def fail(result):
        raise RuntimeError('out of memory')

    monkeypatch.setattr(fuser.runner.network, 'prepare_next', fail)
    fuser.prepare_next()  # the node goes on: no error escapes, the carried features are forgotten
    assert fuser.runner.previous is None
    assert fuser.process(1.5, views).resets == ['temporal']  # the next frame reports it (log, /diagnostics)
    assert fuser.process(2.0, views).resets == []


def test_settings_validate():
    with pytest.raises(ValueError, match='input_kind'):
        FuseSettings(input_kind='pose')
    with pytest.raises(ValueError, match='{view}'):
        FuseSettings(image_topic='/image_raw')
    with pytest.raises(ValueError, match='cpu'):
        FuseSettings(device='cuda')
    s = FuseSettings(gate_m=2.0, score_threshold=0.4)
    assert s.tracker_settings().gate_m == 2.0 and s.decode_overrides() == {'score_threshold': 0.4}


def test_checkpoint_names_a_path_or_a_shipped_file(tmp_path, monkeypatch):
    assert FuseSettings().checkpoint_path() == shipped_checkpoint()
    assert FuseSettings(checkpoint='detector_seed0.pt').checkpoint_path() == shipped_checkpoint('detector_seed0.pt')
    monkeypatch.chdir(tmp_path)  # a file of that name here is taken first: a path is a path
    (tmp_path / 'detector_seed0.pt').write_bytes(b'x')
    assert FuseSettings(checkpoint='detector_seed0.pt').checkpoint_path() == Path('detector_seed0.pt')
    # neither here nor shipped: the path as given, so that loading it names it
    assert FuseSettings(checkpoint='nothing.pt').checkpoint_path() == Path('nothing.pt')
    assert FuseSettings(checkpoint='sub/detector_seed1.pt').checkpoint_path() == Path('sub/detector_seed1.pt')


def test_inputs_made_on_arrival_give_the_same_frames(matrix_sample, model):
    """The fuse node decodes each JPEG and makes its network input as it arrives (``decode_early``); fused
    frames must be exactly those of views made when the frame is complete, the first (decoded in full) included."""
    from matrix_core.fusion.view_inputs import ViewInputs
    from matrix_ros.conversions import image_to_compressed, registration_to_msg

    net, bev = model
    dataset = open_dataset(matrix_sample)
    size = (bev.image_width, bev.image_height)
    fusers = [BevFuser(FuseSettings(area=list(dataset.area)), net, bev) for _ in range(2)]
    inputs = [ViewInputs(size, 0.3, reduced_decode=True) for _ in range(2)]
    for k, frame in enumerate(dataset.frames[:3]):
        messages = {}
        for v in dataset.views:
            ground_H_img = np.linalg.inv(dataset.camera(v, frame).img_H_ground())
            messages[v] = (
                image_to_compressed(dataset.load_image(v, frame)),
                registration_to_msg(Registration(RegistrationStatus.OK, np.eye(3), ground_H_img, confidence=1.0)),
            )
            inputs[1].decode_early(v, messages[v][0])
        views = [{v: x.view_input(v, *m, 'homography') for v, m in messages.items()} for x in inputs]
        assert all(views[1][v].network_image is not None and views[0][v].network_image is None for v in dataset.views)
        plain, early = (f.process(1.0 + 0.5 * k, vs) for f, vs in zip(fusers, views))
        assert len(plain.detections) > 20 and len(plain.tracks) > 20
        np.testing.assert_array_equal(plain.heatmap, early.heatmap)
        np.testing.assert_array_equal(plain.detections.xy, early.detections.xy)
        assert [(t.track_id, *t.xy) for t in plain.tracks] == [(t.track_id, *t.xy) for t in early.tracks]
        for f in fusers:
            f.prepare_next()


def test_reduced_jpeg_decode_gives_the_detections_of_the_full_decode(matrix_sample, model):
    """Real 1920x1080 views as a bag carries them (JPEG): decoded at 1/r size with the homography moved to
    that resolution, the network sees (almost) the same input and finds the same people."""
    import cv2

    net, bev = model
    dataset = open_dataset(matrix_sample)
    r = jpeg_reduction((1920, 1080), (bev.image_width, bev.image_height))  # complex_quick: 320x176 -> 4
    assert r == (4 if bev.image_width <= 480 and bev.image_height <= 270 else 2)
    assert jpeg_reduction((1920, 1080), (480, 272)) == 2 and jpeg_reduction((640, 360), (480, 272)) == 1
    flag = {2: cv2.IMREAD_REDUCED_COLOR_2, 4: cv2.IMREAD_REDUCED_COLOR_4}[r]
    full, small = (BevFuser(FuseSettings(area=list(dataset.area)), net, bev) for _ in range(2))
    for k, frame in enumerate(dataset.frames[:2]):
        views_full, views_small = {}, {}
        for v in dataset.views:
            jpeg = cv2.imencode('.jpg', dataset.load_image(v, frame), [cv2.IMWRITE_JPEG_QUALITY, 95])[1]
            H = dataset.camera(v, frame).img_H_ground()
            views_full[v] = ViewInput(cv2.imdecode(jpeg, cv2.IMREAD_COLOR), H)
            views_small[v] = ViewInput(cv2.imdecode(jpeg, flag), at_reduced_resolution(H, r))
            assert views_small[v].image.shape == (1080 // r, 1920 // r, 3)
        a, b = full.process(1.0 + 0.5 * k, views_full), small.process(1.0 + 0.5 * k, views_small)
        assert len(a.detections) > 20
        diff = np.abs(a.heatmap - b.heatmap)
        d = np.linalg.norm(a.detections.xy[:, None] - b.detections.xy[None], axis=2)
        assert diff.mean() < 0.005 and diff.max() < 0.3
        assert abs(len(a.detections) - len(b.detections)) <= 1 and np.median(d.min(axis=1)) < 0.05
