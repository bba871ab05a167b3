"""Per-drone calibration tracker: one :meth:`DroneCalibrator.process` call per image.

Status of each result:
    - ``ok``: a fresh pose from this image;
    - ``stale``: no acceptable pose in this image (too few corners, ambiguous, implausible jump, high
      reprojection error); ``camera`` is the last good pose and ``age_s`` says how old it is;
    - ``failed``: no good pose yet (since the start); ``camera`` is None, nothing to publish.

Tracked frame (opt-in ``track_corners``, after a good frame whose ORB ground homography to this one succeeded,
with the faster ``track_matcher``, at most ``track_max_frames`` in a row): the board corners that homography
predicts give a pose, which ``grow`` refines (several rounds), verifies and corrects like a detected one;
when that pose passes every check below, the checkerboard search is skipped. Otherwise (the homography is
measured again with ``motion_matcher``), and always for the first frame:

One frame: ORB ground homography from the prior's image (``motion``) -> each board predicted and searched
in a rectified view (``regions``, ``detection``) -> corners named (``assignment``) -> RANSAC/LM PnP
(``pnp``) -> every board corner refined, verified, the position corrected by whole squares and checked
again (``grow``) -> plausibility (reprojection, corners, jump from the prior).

Never returns NaN: a camera is either a finite solved pose or the last good one.
"""

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from matrix_core.calib.assignment import assign_piece
from matrix_core.calib.detection import find_pieces
from matrix_core.calib.pnp import solve_pnp
from matrix_core.calib.grow import best_correction, corrected_correspondences, saddle_map
from matrix_core.calib.motion import GroundMotion
from matrix_core.calib.regions import board_rectification, image_H_board, image_shift, small_gray, translation
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.geometry.camera import Camera, pose_matrix, rotation_angle_deg
from matrix_core.geometry.homography import implied_camera, pixel_scale_homography

OK, STALE, FAILED = 'ok', 'stale', 'failed'
GROW_SHIFT = 4  # largest whole-square correction considered (the initial prior can be squares off)
TRACK_ROUNDS = 5  # at most this many poses re-solved from the saddles they verify, from the predicted corners
SETTLED_DEG, SETTLED_M = 0.03, 0.015  # a re-solved pose this close to the last one has settled
REGISTRATION_SHAPE_ERROR = 0.05  # a registration homography further from a rigid camera is not used


@dataclass
class CalibResult:
    """One frame's outcome; ``camera`` is None only when ``status == 'failed'``."""

    status: str
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


@dataclass
class _Frame:
    """One image while it is calibrated: (H, W) grey pixels, stamp (s), start time, the ORB features and
    small image for the motion (:meth:`DroneCalibrator._motion_data`), stage timings (s)."""

    gray: np.ndarray
    stamp: float
    t_start: float
    motion_data: tuple = None
    guide: Camera = None   # the camera this frame's registration implies, if any
    timings: dict = field(default_factory=dict)

    def finish_timing(self) -> None:
        self.timings['total'] = time.perf_counter() - self.t_start


class DroneCalibrator:
    """Calibrates one drone's camera frame after frame.

    Args:
        scene: boards and intrinsics.
        settings: thresholds.
        initial_prior: pose prior of the first frame (reference calibration or configured), or None.
        initial_image: (H, W[, 3]) image taken at ``initial_prior`` (the reference image), optional: used
            to predict where the boards moved in the first frame.
    """

    def __init__(self, scene: CalibScene, settings: CalibSettings, initial_prior: Camera = None,
                 initial_image: np.ndarray = None):
        self.scene = scene
        self.settings = settings
        self.prior = None if initial_prior is None else scene.camera(initial_prior.cam_T_world)
        self.prior_is_initial = True
        self.tracked_in_a_row = 0   # good frames since the last searched one
        self.last_good = None
        self.last_good_stamp = None
        self.motion = GroundMotion(settings.motion_scale, settings.motion_features, matcher=settings.motion_matcher) \
            if settings.motion_scale > 0 else None
        self.previous_features = self.previous_small = None
        self.previous_gray = None if initial_image is None else self._gray(initial_image)

    def _previous_motion_data(self) -> None:
        """Measure the prior's image for the motion now that a frame needs it (kept as a grey image till then:
        frames guided by a registration never need it)."""
        if self.previous_gray is not None:
            self.previous_features, self.previous_small = self._motion_data(self.previous_gray)
            self.previous_gray = None

    def _motion_data(self, gray: np.ndarray) -> tuple:
        """(ORB features or None, small grey image or None) of this image, for the motion from the prior's."""
        s = self.settings
        features = self.motion.features(gray) if self.motion is not None else None
        small = small_gray(gray, s.global_shift_scale) if s.global_shift_scale > 0 else None
        return features, small

    def _image_motion(self, motion_data: tuple, matcher: str = ''):
        """(cur_H_prev (3, 3) or None, how it was measured, whether it is a full ground homography) from this
        image's ``motion_data`` (ORB ``matcher``, '' = ``motion_matcher``).

        "prev" is the image the prior pose belongs to (the last good frame, or the reference image)."""
        self._previous_motion_data()
        features, small = motion_data
        H, how = None, 'none'
        if features is not None and self.previous_features is not None:
            H, inliers = self.motion.homography(self.previous_features, features, matcher)
            how = f'homography ({inliers} inliers)' if H is not None else f'homography failed ({inliers})'
        homography = H is not None
        if H is None and small is not None and self.previous_small is not None:
            H = translation(image_shift(self.previous_small, small, self.settings.global_shift_scale))
            how = 'shift' if how == 'none' else f'{how}; shift'
        return H, how, homography

    def _predicted_camera(self, predicted: dict):
        """The pose that sees every board corner where ``predicted`` (board name -> (3, 3) current image
        pixels <- corner indices) puts it, or None when too few corners are in view."""
        world, uv = [], []
        for board in self.scene.boards:
            ij = board.corner_indices()
            p = np.c_[ij, np.ones(len(ij))] @ predicted[board.name].T
            front = p[:, 2] > 1e-9
            pix = p[front, :2] / p[front, 2:]
            inside = self.scene.camera(np.eye(4)).in_image(pix, margin=4.0)
            world.append(board.corners_world()[front][inside])
            uv.append(pix[inside])
        world, uv = np.concatenate(world), np.concatenate(uv)
        if len(world) < self.settings.min_corners:
            return None
        fit = solve_pnp(world, uv, self.scene.camera(np.eye(4)), self.settings.ransac_threshold_px)
        return None if fit is None else fit.camera

    @staticmethod
    def _gray(image: np.ndarray) -> np.ndarray:
        if image is None or image.size == 0 or image.dtype != np.uint8 or image.ndim not in (2, 3):
            raise ValueError('expected a non-empty uint8 (H, W) or (H, W, 3) image')
        return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)

    def set_intrinsics(self, K, dist, image_size) -> None:
        """Use other intrinsics from now on (e.g. from a CameraInfo stream)."""
        self.scene = self.scene.with_intrinsics(K, dist, image_size)
        if self.prior is not None:
            self.prior = self.scene.camera(self.prior.cam_T_world)

    def _stale(self, stamp: float, message: str, **kw) -> CalibResult:
        if self.last_good is None:
            return CalibResult(FAILED, None, message=message, **kw)
        return CalibResult(STALE, self.last_good, age_s=float(stamp - self.last_good_stamp), message=message, **kw)

    def _saddles(self, gray, camera) -> list:
        return [saddle_map(gray, camera, board, self.settings.px_per_square, extend=GROW_SHIFT + 1)
                for board in self.scene.boards]

    def _grow(self, gray, camera, rounds: int = 1):
        """(PnPResult or None, whole-square correction or None when ambiguous), see :mod:`grow`.

        The grown pose is verified once more: at the final pose the saddles must put the board exactly
        where the pose does (correction (0, 0)); otherwise the correction counts as ambiguous (None).
        With ``rounds`` > 1 the pose is solved again from the saddles verified at the new pose until it
        settles: a rough starting pose verifies only the corners it predicts to a fraction of a square, and
        corners refined in a view rectified with a wrong pose are biased towards it (measured: a start
        0.2 deg off gave 0.1 deg after one round, 0.015 once settled). Each round is one more saddle pass."""
        maps = self._saddles(gray, camera)
        correction, count = best_correction(maps, GROW_SHIFT)
        if correction is None or count < self.settings.min_corners:
            return None, correction
        total, previous = (0, 0), camera
        for round_ in range(rounds):
            world, uv = corrected_correspondences(maps, correction)
            fit = solve_pnp(world, uv, self.scene.camera(np.eye(4)), self.settings.ransac_threshold_px)
            if fit is None:
                return None, correction
            total = (total[0] + correction[0], total[1] + correction[1])
            maps = self._saddles(gray, fit.camera)
            correction, verified = best_correction(maps, GROW_SHIFT)
            if correction != (0, 0):
                return None, None
            settled = (verified <= count * 1.02 and rotation_angle_deg(fit.camera.R, previous.R) < SETTLED_DEG
                       and np.linalg.norm(fit.camera.center - previous.center) < SETTLED_M)
            if settled or round_ == rounds - 1:
                return fit, total
            count, previous = verified, fit.camera
        return None, None   # not reached

    def process(self, image: np.ndarray, stamp: float, img_H_ground: np.ndarray = None) -> CalibResult:
        """Calibrate from one (H, W, 3) BGR or (H, W) grey uint8 image taken at ``stamp`` seconds.

        ``img_H_ground`` (3, 3), optional: this image's homography from the ground (z = 0, world metres) to
        its pixels, e.g. the inverse of the drone's registration ``H_img_to_ground``. When it implies a rigid
        camera with these intrinsics, that camera predicts the boards (a prior independent of earlier
        frames) and the image motion is not measured."""
        s = self.settings
        t_start = time.perf_counter()
        # Every RANSAC below draws from OpenCV's global RNG: seeding it per image makes the result depend on
        # this image and this drone's history only, not on other drones sharing the process.
        cv2.setRNGSeed(s.seed)
        gray = self._gray(image)
        width, height = self.scene.image_size
        if gray.shape[:2] != (height, width):
            raise ValueError(f'image is {gray.shape[1]}x{gray.shape[0]}, intrinsics are for {width}x{height}')
        if self.prior is None:
            return CalibResult(FAILED, None, message='no pose prior (configure an initial pose)')
        try:
            return self._calibrate(_Frame(gray, stamp, t_start), img_H_ground)
        except cv2.error as exc:   # an OpenCV assertion on one odd frame must not end the drone's calibration
            return self._stale(stamp, f'OpenCV error, frame skipped: {str(exc).strip().splitlines()[-1]}')

    def _registered_camera(self, img_H_ground) -> tuple:
        """(Camera or None, how): the rigid camera a registration's ground homography implies."""
        if img_H_ground is None:
            return None, ''
        H = np.asarray(img_H_ground, dtype=np.float64)
        if H.shape != (3, 3) or not np.all(np.isfinite(H)) or abs(np.linalg.det(H)) < 1e-12:
            return None, 'registration homography unusable; '
        implied = implied_camera(self.scene.K, H)
        if implied.shape_error > REGISTRATION_SHAPE_ERROR:
            return None, f'registration not a rigid camera (shape error {implied.shape_error:.3f}); '
        return self.scene.camera(pose_matrix(implied.R, implied.t)), 'registration'

    def _calibrate(self, frame: _Frame, img_H_ground) -> CalibResult:
        s, timings = self.settings, frame.timings
        guide, guide_how = self._registered_camera(img_H_ground)
        if guide is not None:
            frame.guide = guide
            timings['motion'] = time.perf_counter() - frame.t_start
            predicted = {b.name: image_H_board(guide, b) for b in self.scene.boards}
            if s.track_registered:   # no drift: every registration is to the same reference
                result = self._track(frame, predicted, guide_how)
                if result is not None:
                    return result
            return self._search(frame, predicted, guide, False, guide_how)
        frame.motion_data = self._motion_data(frame.gray)
        track = s.track_corners and not self.prior_is_initial and self.tracked_in_a_row < s.track_max_frames
        cur_H_prev, motion_how, homography = self._image_motion(frame.motion_data,
                                                                s.track_matcher if track else '')
        timings['motion'] = time.perf_counter() - frame.t_start
        if track and homography:
            result = self._track(frame, {b.name: image_H_board(self.prior, b, cur_H_prev) for b in self.scene.boards},
                                 guide_how + motion_how)
            if result is not None:
                return result
        if track and s.track_matcher != s.motion_matcher:   # the search deserves the better prior
            t = time.perf_counter()
            cur_H_prev, motion_how, _ = self._image_motion(frame.motion_data)
            timings['motion_again'] = time.perf_counter() - t
        predicted = {b.name: image_H_board(self.prior, b, cur_H_prev) for b in self.scene.boards}
        return self._search(frame, predicted, self.prior, self.prior_is_initial or cur_H_prev is None,
                            guide_how + motion_how)

    def _track(self, frame: _Frame, predicted: dict, how: str):
        """The OK result of the board corners ``predicted`` puts in the image, refined and verified without a
        checkerboard search (``track_corners``), or None when that pose fails a check."""
        t = time.perf_counter()
        camera = self._predicted_camera(predicted)
        grown, correction = self._grow(frame.gray, camera, TRACK_ROUNDS) if camera is not None else (None, None)
        frame.timings['track'] = time.perf_counter() - t
        if grown is None:
            return None
        result = self._verdict(grown, correction, frame, dict(tracked=True, motion=how, timings_s=frame.timings))
        return result if result.status == OK else None

    def _search(self, frame: _Frame, predicted: dict, prior: Camera, rough: bool, motion_how: str) -> CalibResult:
        """The frame's pose from checkerboard pieces searched where ``predicted`` (board name -> (3, 3) image
        pixels <- corner indices) puts the boards; ``prior`` the pose they were predicted from, ``rough`` when
        that prediction can be metres off (wider search and naming margins)."""
        s, timings, gray, stamp = self.settings, frame.timings, frame.gray, frame.stamp
        t = time.perf_counter()
        margin = s.initial_margin_cells if rough else s.margin_cells
        pieces = []
        for board in self.scene.boards:
            rect = board_rectification(predicted[board.name], board, prior, s.px_per_square, margin)
            if rect is not None:
                pieces += find_pieces(gray, rect[0], rect[1], s.pattern_size, s.max_pieces_per_board,
                                      s.refine_subpixel, s.detect_accuracy)
        full_search = not pieces and s.full_search
        if full_search:
            scale, (width, height) = s.full_search_scale, self.scene.image_size
            img_H_search = None if scale == 1 else pixel_scale_homography(1.0 / scale, 1.0 / scale)
            pieces = find_pieces(gray, img_H_search, (round(width * scale), round(height * scale)), s.pattern_size,
                                 s.max_pieces_per_board * len(self.scene.boards), refine=False,
                                 accuracy=s.detect_accuracy)
        timings['detect'] = time.perf_counter() - t
        t = time.perf_counter()
        info = dict(pieces_found=len(pieces), full_search=full_search, timings_s=timings, motion=motion_how)

        smooth = cv2.GaussianBlur(gray, (3, 3), 0).astype(np.float32)
        jump_deg = s.initial_prior_jump_deg if self.prior_is_initial else s.max_jump_deg
        world, uv, reasons, assigned = [], [], [], 0
        used = set()
        predicted_ij = {name: np.linalg.inv(H) for name, H in predicted.items()}
        max_index_error = s.max_index_error * (4.0 if rough else 1.0)
        for piece in pieces:
            a, why = assign_piece(piece, self.scene.boards, predicted_ij, prior, smooth, max_index_error,
                                  s.ambiguity_ratio, s.index_separation, max(jump_deg, s.max_prior_rotation_deg),
                                  2.0 * s.max_reprojection_px)
            if a is None:
                reasons.append(why)
                continue
            assigned += 1
            for (i, j), p, w in zip(a.indices, a.image_uv, a.world):
                if (a.board.name, i, j) not in used:  # a corner found twice counts once
                    used.add((a.board.name, i, j))
                    world.append(w)
                    uv.append(p)
        timings['assign'] = time.perf_counter() - t
        info['pieces_assigned'] = assigned
        t = time.perf_counter()
        if len(world) < s.min_corners:
            frame.finish_timing()
            why = '; '.join(sorted(set(reasons))) or 'no board piece found'
            return self._stale(stamp, f'{len(world)} corners assigned (< {s.min_corners}): {why}',
                               corners=len(world), **info)
        fit = solve_pnp(np.array(world), np.array(uv), self.scene.camera(np.eye(4)), s.ransac_threshold_px)
        timings['pnp'] = time.perf_counter() - t
        frame.finish_timing()
        if fit is None:
            return self._stale(stamp, 'PnP failed', corners=len(world), **info)
        correction = (0, 0)
        if s.grow_corners and fit.inliers.sum() >= s.min_corners:
            grown, correction = self._grow(gray, fit.camera)
            if correction is None:
                frame.finish_timing()
                return self._stale(stamp, 'ambiguous board position: the board edges that would decide it '
                                   'are out of view', corners=int(fit.inliers.sum()), **info)
            if grown is not None:
                fit = grown
            else:
                correction = (0, 0)
        return self._verdict(fit, correction, frame, info)

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
            return self._stale(stamp, f'implausible jump {move_m:.2f} m / {turn_deg:.1f} deg from the prior',
                               **info)
        if frame.guide is not None:
            apart_m = float(np.linalg.norm(fit.camera.center - frame.guide.center))
            if apart_m > s.registration_agreement_m:
                return self._stale(stamp, f'{apart_m:.2f} m from the camera the registration implies '
                                          f'(> {s.registration_agreement_m})', **info)
        self.prior = self.last_good = fit.camera
        if frame.motion_data is None:   # measured only if the next frame needs it
            self.previous_gray, self.previous_features, self.previous_small = frame.gray, None, None
        else:
            self.previous_gray, (self.previous_features, self.previous_small) = None, frame.motion_data
        self.last_good_stamp = stamp
        self.prior_is_initial = False
        self.tracked_in_a_row = self.tracked_in_a_row + 1 if info.get('tracked') else 0
        note = f'grid corrected by {correction} squares' if correction != (0, 0) else ''
        return CalibResult(OK, fit.camera, 0.0, message=note or 'ok', **info)
