"""Per-drone calibration: one :meth:`DroneCalibrator.process` call per image.

Status of each result:
    - ``ok``: a fresh pose from this image;
    - ``stale``: no acceptable pose in this image (too few corners, ambiguous, implausible jump, high
      reprojection error); ``camera`` is the last good pose and ``age_s`` says how old it is;
    - ``failed``: no good pose yet (since the start); ``camera`` is None, nothing to publish.

Where the boards are predicted from, first match wins:
    1. the frame's registration (a :class:`~matrix_core.register.registration.Registration`), when it implies
       a rigid camera (:mod:`.guided`): its corners are tracked (``track_registered``, :mod:`.corner_tracking`),
       else searched near it;
    2. the prior pose (last good frame, or the initial prior) carried into this image by the image motion
       (:class:`~matrix_core.calib.motion.PriorImageMotion`): opt-in ``track_corners`` tracks the corners
       (after a good frame whose homography with the faster ``track_matcher`` succeeded, at most
       ``track_max_frames`` in a row); otherwise, and always for the first frame, the boards are searched
       (:mod:`.board_search`, incl. the whole-image fallback).
Every pose then passes the plausibility checks (reprojection, corners, jump from the prior, agreement with the
registration) before it becomes the next prior.

Never returns NaN: a camera is either a finite solved pose or the last good one.
"""

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from matrix_core.calib.board_search import search_boards
from matrix_core.calib.corner_tracking import track_corners
from matrix_core.calib.guided import registered_camera, registration_disagreement
from matrix_core.calib.motion import PriorImageMotion
from matrix_core.calib.regions import predict_boards
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.calib.status import CalibStatus
from matrix_core.geometry.camera import Camera, rotation_angle_deg
from matrix_core.register.registration import Registration
from matrix_core.sync.stamp_restart import StampRestart


@dataclass
class CalibResult:
    """One frame's outcome; ``camera`` is None only when ``status`` is ``FAILED``."""

    status: CalibStatus
    camera: Camera = None
    age_s: float = 0.0
    rms_px: float = float('nan')
    corners: int = 0
    pieces_found: int = 0
    pieces_assigned: int = 0
    full_search: bool = False
    tracked: bool = False
    motion: str = ''
    message: str = ''
    timings_s: dict = field(default_factory=dict)

    def diagnostics(self) -> dict:
        """The figures a node reports per image (text values, as diagnostic_msgs/KeyValue carries them)."""
        return {
            'status': str(self.status),
            'reprojection_rms_px': f'{self.rms_px:.3f}',
            'corners': str(self.corners),
            'pieces_found': str(self.pieces_found),
            'pieces_assigned': str(self.pieces_assigned),
            'age_s': f'{self.age_s:.3f}',
            'full_search': str(self.full_search),
            'tracked': str(self.tracked),
            'guide': self.motion,
        }


@dataclass
class _Frame:
    """One image while it is calibrated: (H, W) grey pixels, stamp (s), start time, the ORB features and
    small image for the motion (:meth:`PriorImageMotion.measure`), stage timings (s)."""

    gray: np.ndarray
    stamp: float
    t_start: float
    motion_data: tuple = None
    guide: Camera = None  # the camera this frame's registration implies, if any
    timings: dict = field(default_factory=dict)

    def finish_timing(self) -> None:
        self.timings['total'] = time.perf_counter() - self.t_start


def _gray(image: np.ndarray) -> np.ndarray:
    if image is None or image.size == 0 or image.dtype != np.uint8 or image.ndim not in (2, 3):
        raise ValueError('expected a non-empty uint8 (H, W) or (H, W, 3) image')
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


class DroneCalibrator:
    """Calibrates one drone's camera frame after frame.

    Args:
        scene: boards and intrinsics.
        settings: thresholds.
        initial_prior: pose prior of the first frame (reference calibration or configured), or None.
        initial_image: (H, W[, 3]) image taken at ``initial_prior`` (the reference image), optional: used
            to predict where the boards moved in the first frame.
    """

    def __init__(
        self, scene: CalibScene, settings: CalibSettings, initial_prior: Camera = None, initial_image: np.ndarray = None
    ):
        self.scene = scene
        self.settings = settings
        self.initial = (initial_prior, initial_image)
        self.restart = StampRestart(settings.restart_gap_s)  # fed the stamps of the images processed
        self.went_back = False  # time went back: the next result says it started afresh
        self.start_afresh()

    def start_afresh(self) -> None:
        """Back to the first prior: when made, and when the stamps went back (a replay started over)."""
        initial_prior, initial_image = self.initial
        self.prior = None if initial_prior is None else self.scene.camera(initial_prior.cam_T_world)
        self.prior_is_initial = True
        self.tracked_in_a_row = 0  # good frames since the last searched one
        self.last_good = None
        self.last_good_stamp = None
        self.image_motion = PriorImageMotion(self.settings, None if initial_image is None else _gray(initial_image))

    def check_restart(self, stamp: float) -> None:
        """Start afresh when ``stamp`` (seconds) is more than ``restart_gap_s`` before the images processed (a
        replay started over); :meth:`process` calls it, a node may call it first (before its synchroniser
        takes the new run's messages)."""
        if self.restart.went_back(stamp):  # the old run's last pose is no prior for the new run's first frame
            self.start_afresh()
            self.went_back = True

    @property
    def previous_features(self):
        """ORB features of the prior's image, None until a frame needed them (see :class:`PriorImageMotion`)."""
        return self.image_motion.prior_features

    def set_intrinsics(self, K, dist, image_size) -> bool:
        """Use other intrinsics from now on (e.g. from a CameraInfo stream); False (nothing changed) when they
        equal the current ones."""
        if (
            np.allclose(K, self.scene.K)
            and np.allclose(dist, self.scene.dist)
            and tuple(image_size) == tuple(self.scene.image_size)
        ):
            return False
        self.scene = self.scene.with_intrinsics(K, dist, image_size)
        if self.prior is not None:
            self.prior = self.scene.camera(self.prior.cam_T_world)
        return True

    def process(self, image: np.ndarray, stamp: float, registration: Registration = None) -> CalibResult:
        """Calibrate from one (H, W, 3) BGR or (H, W) grey uint8 image taken at ``stamp`` seconds.

        ``registration``, optional: the drone's registration of this image (failed, unusable or absent: the
        image motion guides). When its ground homography implies a rigid camera with these intrinsics, that
        camera predicts the boards (a prior independent of earlier frames) and the image motion is not
        measured."""
        t_start = time.perf_counter()
        self.check_restart(stamp)
        restarted, self.went_back = self.went_back, False
        # Every RANSAC below draws from OpenCV's global RNG: seeding it per image makes the result depend on
        # this image and this drone's history only, not on other drones sharing the process.
        cv2.setRNGSeed(self.settings.calib_seed)
        gray = _gray(image)
        width, height = self.scene.image_size
        if gray.shape[:2] != (height, width):
            raise ValueError(f'image is {gray.shape[1]}x{gray.shape[0]}, intrinsics are for {width}x{height}')
        if self.prior is None:
            return CalibResult(CalibStatus.FAILED, None, message='no pose prior (configure an initial pose)')
        frame = _Frame(gray, stamp, t_start)
        try:
            guide, how = registered_camera(self.scene, registration)
            how = ('time went back, started afresh; ' if restarted else '') + how
            return self._guided(frame, guide, how) if guide is not None else self._from_prior(frame, how)
        except cv2.error as exc:  # an OpenCV assertion on one odd frame must not end the drone's calibration
            return self._stale(stamp, f'OpenCV error, frame skipped: {str(exc).strip().splitlines()[-1]}')

    def _guided(self, frame: _Frame, guide: Camera, how: str) -> CalibResult:
        """Boards predicted by the camera the frame's registration implies (no image motion measured)."""
        frame.guide = guide
        frame.timings['motion'] = time.perf_counter() - frame.t_start
        predicted = predict_boards(self.scene.boards, guide)
        if self.settings.track_registered:  # no drift: every registration is to the same reference
            result = self._track(frame, predicted, how)
            if result is not None:
                return result
        return self._search(frame, predicted, guide, False, how)

    def _from_prior(self, frame: _Frame, note: str) -> CalibResult:
        """Boards predicted by the prior pose, carried into this image by the image motion; ``note`` (why the
        registration was not used, or '') prefixes the result's ``motion``."""
        s, timings = self.settings, frame.timings
        frame.motion_data = self.image_motion.measure(frame.gray)
        track = s.track_corners and not self.prior_is_initial and self.tracked_in_a_row < s.track_max_frames
        cur_H_prev, how, homography = self.image_motion.since_prior(frame.motion_data, s.track_matcher if track else '')
        timings['motion'] = time.perf_counter() - frame.t_start
        if track and homography:
            result = self._track(frame, predict_boards(self.scene.boards, self.prior, cur_H_prev), note + how)
            if result is not None:
                return result
        if track and s.track_matcher != s.motion_matcher:  # the search deserves the better prior
            t = time.perf_counter()
            cur_H_prev, how, _ = self.image_motion.since_prior(frame.motion_data)
            timings['motion_again'] = time.perf_counter() - t
        predicted = predict_boards(self.scene.boards, self.prior, cur_H_prev)
        return self._search(frame, predicted, self.prior, self.prior_is_initial or cur_H_prev is None, note + how)

    def _track(self, frame: _Frame, predicted: dict, how: str):
        """The OK result of the board corners ``predicted`` puts in the image, refined and verified without a
        checkerboard search, or None when that pose fails a check."""
        t = time.perf_counter()
        fit, correction = track_corners(frame.gray, self.scene, self.settings, predicted)
        frame.timings['track'] = time.perf_counter() - t
        if fit is None:
            return None
        result = self._verdict(fit, correction, frame, dict(tracked=True, motion=how, timings_s=frame.timings))
        return result if result.status is CalibStatus.OK else None

    def _search(self, frame: _Frame, predicted: dict, prior: Camera, rough: bool, how: str) -> CalibResult:
        """The result of the checkerboard search where ``predicted`` puts the boards (see ``search_boards``)."""
        s = self.settings
        max_turn_deg = s.initial_prior_jump_deg if self.prior_is_initial else s.max_jump_deg
        found = search_boards(frame.gray, self.scene, s, predicted, prior, rough, max_turn_deg, frame.timings)
        info = dict(
            pieces_found=found.pieces_found,
            full_search=found.full_search,
            timings_s=frame.timings,
            motion=how,
            pieces_assigned=found.pieces_assigned,
        )
        if found.fit is None:
            frame.finish_timing()
            return self._stale(frame.stamp, found.message, corners=found.corners, **info)
        return self._verdict(found.fit, found.correction, frame, info)

    def _stale(self, stamp: float, message: str, **kw) -> CalibResult:
        if self.last_good is None:
            return CalibResult(CalibStatus.FAILED, None, message=message, **kw)
        return CalibResult(
            CalibStatus.STALE, self.last_good, age_s=float(stamp - self.last_good_stamp), message=message, **kw
        )

    def _verdict(self, fit, correction: tuple, frame: _Frame, info: dict) -> CalibResult:
        """Accept ``fit`` (a PnPResult, grid-corrected by ``correction`` squares) as this frame's pose when it
        is plausible, and make it the next prior; otherwise the stale result saying why."""
        s, stamp = self.settings, frame.stamp
        frame.finish_timing()
        n_in = int(fit.inliers.sum())
        info = dict(info, corners=n_in, rms_px=fit.rms_px)
        if n_in < s.min_corners:
            return self._stale(stamp, f'{n_in} PnP inliers (< {s.min_corners})', **info)
        if fit.rms_px > s.max_reprojection_px:
            return self._stale(stamp, f'reprojection RMS {fit.rms_px:.2f} px > {s.max_reprojection_px}', **info)
        jump_m = s.initial_prior_jump_m if self.prior_is_initial else s.max_jump_m
        jump_deg = s.initial_prior_jump_deg if self.prior_is_initial else s.max_jump_deg
        move_m = float(np.linalg.norm(fit.camera.center - self.prior.center))
        turn_deg = rotation_angle_deg(fit.camera.R, self.prior.R)
        if move_m > jump_m or turn_deg > jump_deg:
            return self._stale(stamp, f'implausible jump {move_m:.2f} m / {turn_deg:.1f} deg from the prior', **info)
        disagreement = registration_disagreement(fit.camera, frame.guide, s) if frame.guide is not None else ''
        if disagreement:
            return self._stale(stamp, disagreement, **info)
        self.prior = self.last_good = fit.camera
        self.image_motion.remember(frame.gray, frame.motion_data)
        self.last_good_stamp = stamp
        self.prior_is_initial = False
        self.tracked_in_a_row = self.tracked_in_a_row + 1 if info.get('tracked') else 0
        note = f'grid corrected by {correction} squares' if correction != (0, 0) else ''
        return CalibResult(CalibStatus.OK, fit.camera, 0.0, message=note or 'ok', **info)
