"""Calibration guided by the drone's registration (``DroneCalibrator.process(..., registration)``), on the
real MATRIX sample: the registration of each frame to the drone's reference implies a camera that predicts
the boards; their corners are refined and verified without a checkerboard search (``track_registered``)."""

import cv2
import numpy as np
import pytest

from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.status import CalibStatus
from matrix_core.calib.evaluation import pose_errors
from matrix_core.calib.scene import load_scene
from matrix_core.calib.settings import CalibSettings
from matrix_core.datasets import MatrixDataset
from matrix_core.register.registrar import Registrar
from matrix_core.register.registration import Registration
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings

cv2.setNumThreads(1)


@pytest.fixture(scope='module')
def dataset(matrix_sample):
    return MatrixDataset(matrix_sample)


def _drone(dataset, view, settings=None):
    reference = dataset.reference_image(view)
    camera = dataset.reference_camera(view)
    register_settings, _ = settings_for_dataset(RegisterSettings(), dataset)
    return (
        DroneCalibrator(load_scene(), settings or CalibSettings(), camera, reference),
        Registrar(register_settings, reference, camera, dataset.area, f'{view}/reference'),
    )


@pytest.mark.slow  # 40 real 1080p views: 8 s
def test_every_real_frame_is_calibrated_from_its_registration(dataset):
    """All 8 drones x 5 frames: ok, no board search, no image-motion features, median within 0.03 deg / 2 cm
    and every frame within 0.15 deg / 7 cm of the stored calibration (searching gets 32 of 40 frames, worst
    0.17 deg / 5.6 cm). The worst frame (D2 frame 0, registered with 28 inliers) is 6.4 cm on an Intel Xeon
    and was under 6 cm on the AMD EPYC machines before; its rotation is 0.089 deg on an AMD EPYC with AVX-512
    and 0.109 deg / 6.3 cm on one without (the same code): OpenCV's SIFT differs in the last bits
    between CPU vector paths, so the bound on the worst frame leaves room for that; the medians (0.015 deg /
    0.7 cm here) keep the test tight."""
    rots, centres = [], []
    for view in dataset.views:
        calibrator, registrar = _drone(dataset, view)
        for index, frame in enumerate(dataset.frames):
            image = dataset.load_image(view, frame)
            registration = registrar.register(image, frame)
            assert registration.ok, (view, frame, registration.message)
            r = calibrator.process(image, 0.5 * index, registration)
            assert r.status == CalibStatus.OK and r.tracked and r.motion == 'registration', (view, frame, r.message)
            assert 'detect' not in r.timings_s and calibrator.previous_features is None
            rot, centre = pose_errors(r.camera, dataset.camera(view, frame))
            rots.append(rot)
            centres.append(centre)
    assert np.median(rots) < 0.03 and np.median(centres) < 0.02, (np.median(rots), np.median(centres))
    assert max(rots) < 0.15 and max(centres) < 0.07, (max(rots), max(centres))


def test_an_unusable_registration_falls_back_to_the_image_motion(dataset):
    calibrator, _ = _drone(dataset, 'D5')
    truth = dataset.camera('D5', 0)
    not_rigid = truth.img_H_ground() @ np.diag([1.0, 1.3, 1.0])  # squashed: no camera with this K
    for k, (H, why) in enumerate(
        [(np.full((3, 3), np.nan), 'registration homography unusable'), (not_rigid, 'registration not a rigid camera')]
    ):
        r = calibrator.process(dataset.load_image('D5', k), 0.5 * k, Registration.from_img_H_ground(H))
        assert r.status == CalibStatus.OK and r.motion.startswith(why) and 'homography (' in r.motion, r.motion
        assert 'detect' in r.timings_s  # searched where the image motion put the boards


def test_a_pose_that_disagrees_with_the_registration_is_rejected(dataset):
    """A registration 0.5 m (2 squares) or 1.5 m off: the board pose found is the true one, which the
    registration contradicts; the frame is not ok (two estimates disagree), never published as good."""
    for shift_m in (0.5, 1.5):
        calibrator, registrar = _drone(dataset, 'D5', CalibSettings(full_search=False))
        image = dataset.load_image('D5', 0)
        registration = registrar.register(image, 0)
        ground_T_moved = np.array([[1.0, 0.0, shift_m], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
        wrong = np.linalg.inv(registration.ground_H_img) @ np.linalg.inv(ground_T_moved)
        r = calibrator.process(image, 0.0, Registration.from_img_H_ground(wrong))
        assert r.status == CalibStatus.FAILED and r.camera is None, r.message
        apart_m = float(r.message.split(' m from the camera the registration implies (> 0.3)')[0])
        assert abs(apart_m - shift_m) < 0.05, r.message
