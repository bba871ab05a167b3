"""Registration of one drone's frames to its reference: features -> symmetric matches -> robust homography
-> sanity gate -> result; with re-keying to a recent good frame when confidence stays low, and a way
back: while re-keyed, the original reference is tried again every ``retry_reference_every`` frames and
whenever the chained registration is weak, and takes over again when it registers well (chains
accumulate error; the reference does not).

Mode ``track`` (:mod:`matrix_core.register.flow_tracking`): frames between anchors are registered by optical
flow from the previous frame, refined against the anchor and chained to the anchor's registration; an anchor is a
full registration as above, made on the first frame, every ``reanchor_every`` frames, after a failure, and
whenever the chain is doubted (too few flow inliers, or the sanity gate rejects the chained homography).
The anchor after a doubted chain describes features only where the chain's own estimate puts the reference's
ground (:mod:`matrix_core.register.search_region`), and the whole image only when that fails.
With ``anchor_by_flow`` an anchor is first tried against the reference image itself by the same flow and
refinement (the reference is then the anchor of a one-frame chain), which costs a tracked frame instead of
a feature extraction and matching; the features run only when that fails."""

import time
from dataclasses import replace

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.register.backends import make_backend
from matrix_core.register.features import Features
from matrix_core.register.fit import fit_homography
from matrix_core.register.flow_tracking import FlowStart, FlowTracker, TrackImages, registered_camera
from matrix_core.register.gate import check_registration
from matrix_core.register.ground_mask import ground_mask
from matrix_core.register.matching import match_symmetric
from matrix_core.register.reference import Reference
from matrix_core.register.search_region import predicted_region
from matrix_core.register.registration import Registration, RegistrationStatus
from matrix_core.register.settings import RegisterSettings

# Mode track, anchor_by_flow: after this many anchors by flow failed in a row, only due anchors try it (on
# simulated complex seed 3 most doubted chains anchor by flow; on the real sample, whose reference images
# were filmed at another time, none does).
FLOW_ANCHOR_TRIES = 2


class Registrar:
    """Registers the frames of ONE drone (call :meth:`register` in frame order).

    Args:
        settings: :class:`RegisterSettings`.
        reference_image: (H, W, 3) BGR reference image (or the first good frame).
        reference_camera: its calibration (internal convention).
        area: (x_min, y_min, x_max, y_max) of the scene ground, internal world metres.
        reference_id: name used in results, e.g. 'D1/reference'.
        backend: a feature backend to share between drones (default: built from ``settings``).
    """

    def __init__(
        self,
        settings: RegisterSettings,
        reference_image: np.ndarray,
        reference_camera: Camera,
        area,
        reference_id: str = 'reference',
        backend=None,
    ):
        self.settings = s = settings
        self.backend = backend if backend is not None else make_backend(s)
        h, w = reference_image.shape[:2]
        if (w, h) != (reference_camera.width, reference_camera.height):
            raise ValueError(
                f'{reference_id}: image is {w}x{h} but its calibration is '
                f'{reference_camera.width}x{reference_camera.height}'
            )
        features = self.backend.extract(reference_image, s.reference_max_features)
        self.reference = Reference(
            reference_id, reference_camera, features, area, s.ground_only, s.ground_margin_m, s.exclude_boxes
        )
        self.key = None
        self._previous_center = None
        self._frames_since_good = 1
        self._weak_streak = 0
        self._frames_on_key = 0  # frames registered since the last re-keying
        self._last_good = None  # (frame_id, features, ref_H_img)
        self.tracker = FlowTracker(
            s.scale, s.flow_corners, s.homography_ransac_px, s.estimator, s.registration_seed, s.track_refine_scale
        )
        self._track = None  # the FlowStart of the last registered frame (mode track), None: next one anchors
        # mode track, anchor_by_flow: the reference as a chain's anchor (its reduced images and ground corners)
        self._reference_track = None
        self._flow_anchor_failures = 0  # anchors by flow that did not hold in a row
        # mode track: the reference's ground at the features' scale, where a doubted chain's anchor searches
        self._reference_ground = None
        if s.mode == 'track' and s.ground_only and s.anchor_search_margin_px > 0:
            self._reference_ground = ground_mask(reference_camera, s.scale, area, s.ground_margin_m, s.exclude_boxes)
        if s.mode == 'track' and s.anchor_by_flow:
            self._reference_track = self.tracker.anchor(
                self.tracker.reduce(reference_image),
                reference_camera,
                np.eye(3),
                reference_id,
                len(self.reference.features),
                area,
                s.ground_margin_m,
                s.exclude_boxes,
            )

    @property
    def reference_id(self) -> str:
        base = self.reference.reference_id
        return base if self.key is None else f'{base}<-{self.key.key_id}'

    def _target(self):
        """(features to match against, (3, 3) target pixels -> reference pixels)."""
        if self.key is None:
            return self.reference.features, np.eye(3)
        return self.key.features, self.key.key_to_ref

    def register(self, image: np.ndarray, frame_id='') -> Registration:
        """Register one (H, W, 3) BGR current image; see :class:`Registration` for the output."""
        start = time.perf_counter()
        cam = self.reference.camera
        h, w = image.shape[:2]
        if (w, h) != (cam.width, cam.height):
            self._track = None
            return self._result(
                RegistrationStatus.FAILED,
                None,
                0,
                0,
                float('nan'),
                start,
                f'image is {w}x{h}, the reference is {cam.width}x{cam.height}',
            )
        if self.settings.mode != 'track':
            return self._register_full(image, frame_id, start)
        images = self.tracker.reduce(image)
        state, every = self._track, self.settings.reanchor_every
        due = bool(state is not None and every and state.steps + 1 >= every)
        tracked, why, predicted = self._flow(images, start)
        if tracked is not None:
            return tracked
        anchored, why_not = self._anchor_by_flow(images, frame_id, start, due)
        if anchored is not None:
            return replace(anchored, message=f'anchor by flow to the reference: {why}')
        why = f'{why}; by flow to the reference: {why_not}' if why_not else why
        result = self._register_full(image, frame_id, start, self._search_region(predicted))
        self._anchor(images, result, frame_id)
        return replace(
            result,
            message='; '.join(filter(None, [f'anchor: {why}', result.message])),
            seconds=time.perf_counter() - start,
        )

    def _search_region(self, ref_H_cur) -> np.ndarray:
        """(h, w) bool where the current image can show the reference's ground by the prediction ``ref_H_cur``
        (None: no prediction, re-keyed or masking off: the whole image)."""
        if ref_H_cur is None or self._reference_ground is None or self.key is not None:
            return None
        return predicted_region(
            self._reference_ground, ref_H_cur, self.settings.scale, self.settings.anchor_search_margin_px
        )

    def _register_full(self, image: np.ndarray, frame_id, start, region: np.ndarray = None) -> Registration:
        """Features of ``image`` (full-size BGR or grey) matched to the reference or key frame; only within
        ``region`` ((h, w) bool, :meth:`_search_region`) first when given, the whole image if that fails."""
        s = self.settings
        cur = self.backend.extract(image, s.max_features, region)
        notes = []
        result = None
        if self.key is not None and self._retry_due():
            result = self._back_to_reference(cur, start, notes)
        if result is None:
            result = self._attempt(cur, *self._target(), start)
            if region is not None and result.ok:
                notes.append('features within the predicted ground')
            elif region is not None:  # the prediction may have been wrong: the whole image
                notes.append(f'not registered within the predicted ground ({result.message}), the whole image')
                cur = self.backend.extract(image, s.max_features)
                result = self._attempt(cur, *self._target(), start)
            if self.key is not None and s.retry_reference_every and self._weak(result) and not notes:
                # The chained registration degrades: the original reference may be visible again.
                result = self._back_to_reference(cur, start, notes) or result
        if result.ok:
            self._previous_center = result.implied_center
        note = self._update_key(result, frame_id, cur)
        notes += [note] if note else []
        if notes:
            message = '; '.join(([result.message] if result.message else []) + notes)
            result = replace(result, message=message)
        return replace(result, seconds=time.perf_counter() - start)

    def _flow(self, images: TrackImages, start) -> tuple:
        """(tracked Registration, '', None) when the flow from the previous frame holds, else (None, why it
        does not: the reason of the anchor that follows, the chain's (3, 3) estimate of ``ref_H_cur``: the
        refined fit with too few inliers, or the flow step alone; None when there is none or the gate
        rejected it)."""
        s, state = self.settings, self._track
        if state is None:
            return None, 'no registered previous frame', None
        if s.reanchor_every and state.steps + 1 >= s.reanchor_every:
            return None, f'due (every {s.reanchor_every} frames)', None
        step = self.tracker.step(state, images)
        anchor = state.anchor
        if step.anchor_H_cur is None:  # the flow step alone, chained to the previous frame, still predicts
            predicted = None if step.prev_H_cur is None else anchor.ref_H_img @ state.anchor_H_img @ step.prev_H_cur
            return None, f'chain doubted: {step.reason}', predicted
        H = anchor.ref_H_img @ step.anchor_H_cur
        H = H / H[2, 2]
        if step.inliers < s.track_min_inliers:
            return None, f'chain doubted: {step.inliers} flow inliers (track_min_inliers {s.track_min_inliers})', H
        cam = self.reference.camera
        reason, implied = check_registration(
            H,
            cam.K,
            cam.img_H_ground(),
            cam.center,
            self.reference.polygon,
            self._previous_center,
            self._frames_since_good,
            s.gate_max_shape_error,
            s.gate_max_area_ratio,
            s.gate_max_height_change_m,
            s.gate_max_step_m,
            anchor.inliers,
            s.gate_shape_inliers,
        )
        if reason:
            return None, f'chain doubted: {reason}', None
        self._previous_center, self._frames_since_good = implied.center, 1
        steps = state.steps + 1
        self._track = FlowStart(anchor, images, step.corners, step.anchor_H_cur, steps, step.prev_H_cur)
        return (
            self._result(
                RegistrationStatus.OK,
                H,
                step.tracked,
                step.inliers,
                step.error_px,
                start,
                f'tracked: {steps} frame(s) after its anchor',
                anchor.chain,
                implied,
            ),
            '',
            None,
        )

    def _anchor_by_flow(self, images: TrackImages, frame_id, start, due: bool) -> tuple:
        """(Registration, '') of the frame of ``images`` refined against the reference's own ground corners, which
        starts a new chain; (None, why not) when it does not hold (then features decide) or is not tried ('').

        The prediction comes from the last registered frame when there is one (its flow, chained to the
        reference), else from the reference itself (flow from the reference image: the drone hovers near its
        reference pose). After ``FLOW_ANCHOR_TRIES`` failed tries in a row, the next is made only when an
        anchor is ``due`` on a sound chain (a reference filmed at another time may never hold, as on the real
        sample; each failed try costs a flow step)."""
        state, reference = self._track, self._reference_track
        if reference is None or self.key is not None or (self._flow_anchor_failures >= FLOW_ANCHOR_TRIES and not due):
            return None, ''
        result, why_not = self._flow_to_reference(images, frame_id, start, state, reference)
        self._flow_anchor_failures = 0 if result is not None else self._flow_anchor_failures + 1
        return result, why_not

    def _flow_to_reference(self, images: TrackImages, frame_id, start, state, reference) -> tuple:
        """:meth:`_anchor_by_flow` from ``state`` (or the reference's own FlowStart when None)."""
        s = self.settings
        if state is not None:  # the previous frame, seen from the reference: the flow predicts ref_H_cur
            state = replace(state, anchor=reference.anchor, anchor_H_img=state.anchor.ref_H_img @ state.anchor_H_img)
        step = self.tracker.step(state or reference, images)
        if step.anchor_H_cur is None:
            return None, step.reason
        if step.inliers < s.track_min_inliers:
            return None, f'{step.inliers} inliers (track_min_inliers {s.track_min_inliers})'
        H = step.anchor_H_cur / step.anchor_H_cur[2, 2]
        cam = self.reference.camera
        reason, implied = check_registration(
            H,
            cam.K,
            cam.img_H_ground(),
            cam.center,
            self.reference.polygon,
            self._previous_center,
            self._frames_since_good,
            s.gate_max_shape_error,
            s.gate_max_area_ratio,
            s.gate_max_height_change_m,
            s.gate_max_step_m,
            step.inliers,
            s.gate_shape_inliers,
        )
        if reason:
            return None, reason
        self._previous_center, self._frames_since_good = implied.center, 1
        result = self._result(
            RegistrationStatus.OK, H, step.tracked, step.inliers, step.error_px, start, '', None, implied
        )
        self._anchor(images, result, frame_id)
        return result, ''

    def _anchor(self, images: TrackImages, result: Registration, frame_id) -> None:
        """Start a new chain at a full registration (none after a failure: the next frame anchors again)."""
        self._track = None
        if result.ok:
            s = self.settings
            self._track = self.tracker.anchor(
                images,
                registered_camera(self.reference.camera, result.implied),
                result.ref_H_img,
                f'{result.reference_id}<-track:{frame_id}',
                result.inliers,
                self.reference.area,
                s.ground_margin_m,
                s.exclude_boxes,
            )

    def reference_result(self) -> Registration:
        """The result of the reference image itself (identity, exact by definition), for a caller that made
        a live image the reference. It does not seed the gate's previous camera centre: the reference may be
        from another time than the frames that follow."""
        n = len(self.reference.features)
        return self._result(
            RegistrationStatus.OK, np.eye(3), n, n, 0.0, time.perf_counter(), 'this image is the reference'
        )

    def _weak(self, result: Registration) -> bool:
        return not result.ok or result.confidence < self.settings.rekey_confidence

    def _retry_due(self) -> bool:
        """While re-keyed: retry the original reference every ``retry_reference_every`` frames."""
        every = self.settings.retry_reference_every
        return bool(every) and self._frames_on_key > 0 and self._frames_on_key % every == 0

    def _back_to_reference(self, cur: Features, start, notes: list):
        """Register ``cur`` to the original reference; a good result ends the re-keying (returned), else
        None (the key frame stays). Appends what happened to ``notes`` (diagnostics)."""
        key_id = self.key.key_id
        direct = self._attempt(cur, self.reference.features, np.eye(3), start, self.reference.reference_id)
        if direct.ok and direct.confidence >= self.settings.good_confidence:
            self.key = None
            self._weak_streak = 0
            notes.append(f'back on the reference (retried after {self._frames_on_key} frames on {key_id})')
            return direct
        why = direct.message if not direct.ok else f'confidence {direct.confidence:.2f}'
        notes.append(f'reference retried, stays on {key_id} ({why})')
        return None

    def _attempt(
        self, cur: Features, target: Features, target_to_ref: np.ndarray, start, reference_id: str = None
    ) -> Registration:
        """Match ``cur`` to ``target`` (whose pixels map to the reference's by ``target_to_ref``), fit, gate."""
        s = self.settings
        cam = self.reference.camera
        cv2.setRNGSeed(s.registration_seed)  # OpenCV's global RNG, per registration: same frames, same fit
        pairs = match_symmetric(cur.desc, target.desc, s.ratio, s.matcher)
        # Fit in reference pixels, so that the inlier threshold is in full-resolution reference pixels.
        dst = (
            cv2.perspectiveTransform(target.xy[pairs[:, 1]].reshape(-1, 1, 2), target_to_ref).reshape(-1, 2)
            if len(pairs)
            else np.zeros((0, 2))
        )
        fit = fit_homography(
            cur.xy[pairs[:, 0]], dst, s.estimator, s.homography_ransac_px, s.ransac_iterations, seed=s.registration_seed
        )
        matches, inliers = len(pairs), int(fit.inliers.sum())
        args = (matches, inliers, fit.error_px, start)
        if fit.H is None:
            return self._result(
                RegistrationStatus.FAILED, None, matches, 0, float('nan'), start, fit.reason, reference_id
            )
        if inliers < s.min_inliers:
            return self._result(
                RegistrationStatus.FAILED,
                None,
                *args,
                f'only {inliers} inliers (min_inliers {s.min_inliers})',
                reference_id,
            )
        reason, implied = check_registration(
            fit.H,
            cam.K,
            cam.img_H_ground(),
            cam.center,
            self.reference.polygon,
            self._previous_center,
            self._frames_since_good,
            s.gate_max_shape_error,
            s.gate_max_area_ratio,
            s.gate_max_height_change_m,
            s.gate_max_step_m,
            inliers,
            s.gate_shape_inliers,
        )
        if reason:
            return self._result(RegistrationStatus.FAILED, None, *args, reason, reference_id)
        return self._result(RegistrationStatus.OK, fit.H, *args, '', reference_id, implied)

    def _result(
        self, status, H, matches, inliers, error_px, start, message='', reference_id=None, implied=None
    ) -> Registration:
        ground_H_img = None
        if H is not None:
            ground_H_img = self.reference.camera.ground_H_img() @ H
            ground_H_img = ground_H_img / ground_H_img[2, 2]
        return Registration(
            status,
            H,
            ground_H_img,
            inliers / matches if matches else 0.0,
            matches,
            inliers,
            error_px,
            reference_id or self.reference_id,
            self.backend.name,
            time.perf_counter() - start,
            message,
            implied,
        )

    def _update_key(self, result: Registration, frame_id, cur: Features) -> str:
        """Track good frames; after ``rekey_after`` weak frames in a row, chain through the last good one."""
        s = self.settings
        self._frames_since_good = 1 if result.ok else self._frames_since_good + 1
        self._frames_on_key = self._frames_on_key + 1 if self.key is not None else 0
        if result.ok and result.confidence >= s.good_confidence:
            self._last_good = (frame_id, cur, result.ref_H_img)
        self._weak_streak = self._weak_streak + 1 if self._weak(result) else 0
        if s.rekey_after and self._weak_streak >= s.rekey_after and self._last_good is not None:
            frame, features, H = self._last_good
            key_id = f'key:{frame}'
            if self.key is None or self.key.key_id != key_id:
                self.key = self.reference.make_key(key_id, features, H)
                self._weak_streak = 0
                self._frames_on_key = 0
                return f're-keyed: next frames register to frame {frame}, chained to the reference'
        return ''
