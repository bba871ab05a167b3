"""Registration that tracks: the previous frame's ground corners followed into the current frame.

Between consecutive frames (0.5 s apart) a drone's image moves little, so instead of describing and matching
features against the reference, a frame is registered from the last one, in two steps:

1. flow, at the registration's reduced scale (480x270): the previous frame's ground corners are tracked into
   the current frame by pyramidal Lucas-Kanade (forward-backward checked) and a robust ``prev_H_cur`` is
   fitted; chained, ``anchor_H_prev @ prev_H_cur`` predicts where the current frame lies in the ANCHOR frame
   (the last fully registered one);
2. refinement against the anchor, at the finer ``refine_scale`` (960x540): the current image is warped into
   the anchor frame by that prediction, the anchor's own ground corners are tracked into the warped image
   (small residual motion, the ground's perspective change already undone by the warp) and ``anchor_H_cur``
   is fitted to them directly. At twice the flow's resolution a corner is located twice as finely, so more
   of the anchor's corners agree within the inlier threshold of a full-resolution pixel (fewer chains are
   doubted, each costing a full registration) and the fit is tighter (docs/registration.md).

Step 2 makes each frame one hop from its anchor: the error of the flow steps does not add up along the
chain (measured: chained flow steps alone drift by about 0.2 px per frame). The caller chains
``ref_H_cur = ref_H_anchor @ anchor_H_cur`` (``matrix_core.register.registrar``, mode ``track``).

Anchor corners are kept only where the registered camera sees the scene ground (the reference's ground mask,
:func:`~matrix_core.register.ground_mask.ground_pixels`, with the camera the registration implies): facades,
the block and the sky do not follow the ground homography; people do not either and fall out as outliers.
Coordinates: pixel centres of the image they were found in (flow corners: the flow image; an anchor's corners:
its refinement image) inside the states, full-resolution pixels for every homography.
"""

from dataclasses import dataclass

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.homography import ImpliedCamera, apply_homography, pixel_scale_homography
from matrix_core.register.features import resize, scaled_size, to_gray
from matrix_core.register.fit import fit_homography
from matrix_core.register.ground_mask import ground_pixels

# Flow: an 11 px window on 5 pyramid levels (0-4) follows ~80 reduced px (320 full-res px) of motion, more
# than a MATRIX drone moves in 0.5 s (up to ~240 full-res px); the last step's motion predicts the next. The
# step only predicts the refinement's warp: 11 px instead of 15 (half the pixels per corner) registered the same
# frames as exactly (scripts/bench_register.py, real sample and simulated seeds 3 and 11).
FLOW_WINDOW, FLOW_LEVELS = (11, 11), 4
# Refinement: the residual after the warp is about a pixel; a small window keeps the local planar model. Its
# side in flow-image pixels (the ground it covers); in refinement-image pixels it is this times refine_scale /
# scale, rounded down to odd: 19 px at 960x540 (measured against 13-21 px on simulated complex seeds 3 and 11:
# smaller windows let a frame slip, larger ones cost CPU), 9 px when the refinement runs at the flow's own scale.
REFINE_WINDOW_FLOW_PX = 9.5
# Pyramid levels above the refinement image: at 960x540 none (the residual, 1-2 px, is well inside the window;
# a second level was dearer and no more exact on the simulated seeds); at the flow's own scale one.
REFINE_LEVELS_FINE, REFINE_LEVELS_FLOW_SCALE = 0, 1
LK_CRITERIA = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 10, 0.01)
# A corner is kept when tracking it back lands within this many pixels (of the image tracked in) of where it
# started.
FORWARD_BACKWARD_PX = 0.1
# The flow step only predicts (the refinement against the anchor, checked both ways, decides): its corners are
# tracked forward only and its robust fit rejects the bad ones; the backward pass was half the step's CPU time.
FLOW_BACKWARD_CHECK = False
# The refinement is repeated from its own result while its inliers still move by more than this (full-resolution
# px, median) from where the warp put them, at most REFINE_PASSES times: one pass corrects a prediction a pixel
# off, but a flow step 6 full-res px off (simulated complex seed 3, D2 frame 94) ended 6.5 px off after one
# pass and 0.8 px after two (its first pass moved the inliers by 0.8-1.2 full-res px: a bound of 1.2 missed it).
REFINE_CONVERGED_PX = 0.8
REFINE_PASSES = 3
# Inlier threshold (full-resolution pixels) of the refined fit: well-tracked ground corners agree to a pixel,
# slowly walking people do not.
REFINE_THRESHOLD_PX = 1.0
# Corner detection (reduced image): a low quality level (relative to the strongest corner, usually a lit
# window or a person) because the plaza's concrete is weakly textured; 10 px apart spreads them out.
CORNER_QUALITY = 1e-4
CORNER_MIN_DISTANCE = 10


@dataclass(frozen=True)
class TrackImages:
    """One frame's grey images for tracking: ``flow`` (h, w) uint8 at the flow's scale, ``refine`` (h', w') uint8
    at the refinement's scale (the same array when the scales are equal)."""

    flow: np.ndarray
    refine: np.ndarray


@dataclass(frozen=True)
class Anchor:
    """A fully registered frame that the next frames are refined against.

    Attributes:
        images: its :class:`TrackImages`; corners: (N, 1, 2) float32 its ground corners (refinement-image pixels).
        ref_H_img: (3, 3) its registration (full-resolution pixels -> reference pixels).
        chain: reference_id of the frames registered through it, e.g. 'D1/reference<-track:17'.
        inliers: inliers of its full registration (the tolerance of the sanity gate, see gate.py).
    """

    images: TrackImages
    corners: np.ndarray
    ref_H_img: np.ndarray
    chain: str
    inliers: int


@dataclass(frozen=True)
class FlowStart:
    """The last registered frame, what the next frame's flow starts from.

    Attributes:
        anchor: the :class:`Anchor` of the chain.
        images: its :class:`TrackImages`; corners: (M, 1, 2) float32 its corners (flow-image pixels).
        anchor_H_img: (3, 3) its pixels -> the anchor's pixels (full resolution; identity for the anchor).
        steps: frames registered through the anchor since it (0 for the anchor itself).
        prev_H_cur: (3, 3) its own flow step (full resolution), predicts the next one; None for the anchor.
    """

    anchor: Anchor
    images: TrackImages
    corners: np.ndarray
    anchor_H_img: np.ndarray
    steps: int = 0
    prev_H_cur: np.ndarray = None


@dataclass(frozen=True)
class FlowStep:
    """One frame registered from the last one.

    Attributes:
        anchor_H_cur: (3, 3) current full-resolution pixels -> anchor pixels, or None (see ``reason``).
        prev_H_cur: (3, 3) the flow step, current -> previous full-resolution pixels (None if it failed).
        tracked: anchor corners that passed the refinement's forward-backward check; inliers: of them, inliers.
        error_px: mean inlier reprojection error, full-resolution anchor pixels (NaN if none).
        corners: (K, 1, 2) float32 the inliers' positions in the current flow image (the next flow's start).
        reason: why anchor_H_cur is None ('' otherwise).
    """

    anchor_H_cur: np.ndarray
    prev_H_cur: np.ndarray
    tracked: int
    inliers: int
    error_px: float
    corners: np.ndarray = None
    reason: str = ''


def _track(a: np.ndarray, b: np.ndarray, pa: np.ndarray, guess, window, levels, backward: bool = True) -> tuple:
    """LK of (N, 1, 2) ``pa`` from image ``a`` into ``b`` (starting at ``guess`` if given) and back:
    ((N, 1, 2) positions in ``b``, (N,) bool tracked both ways and back within FORWARD_BACKWARD_PX; with
    ``backward`` false: tracked forward)."""
    flags = cv2.OPTFLOW_USE_INITIAL_FLOW if guess is not None else 0
    pb, ok, _ = cv2.calcOpticalFlowPyrLK(
        a, b, pa, guess, winSize=window, maxLevel=levels, criteria=LK_CRITERIA, flags=flags
    )
    if not backward:
        return pb, ok.ravel().astype(bool)
    back, ok_back, _ = cv2.calcOpticalFlowPyrLK(
        b, a, pb, pa.copy(), winSize=window, maxLevel=levels, criteria=LK_CRITERIA, flags=cv2.OPTFLOW_USE_INITIAL_FLOW
    )
    fb = np.linalg.norm((back - pa).reshape(-1, 2), axis=1)
    return pb, ok.ravel().astype(bool) & ok_back.ravel().astype(bool) & (fb < FORWARD_BACKWARD_PX)


class FlowTracker:
    """Ground corners and flow at ``scale``, refinement at ``refine_scale`` of the full image.

    Args:
        scale: flow image / full image size (the registration's ``scale``).
        refine_scale: refinement image / full image size (at least ``scale``; RegisterSettings.track_refine_scale).
        max_corners: corners detected per anchor (strongest first, before the ground mask).
        threshold_px: inlier threshold of the flow step's robust fit, full-resolution pixels.
        estimator: 'magsac' or 'ransac' (:func:`~matrix_core.register.fit.fit_homography`); seed: its seed.
    """

    def __init__(
        self,
        scale: float,
        max_corners: int,
        threshold_px: float,
        estimator: str = 'magsac',
        seed: int = 0,
        refine_scale: float = None,
    ):
        self.scale = scale
        self.refine_scale = max(scale, refine_scale or scale)
        self.max_corners = max_corners
        self.threshold_px = threshold_px
        self.estimator = estimator
        self.seed = seed
        # full-resolution pixels <-> reduced pixels (pixel-centre convention of features.to_full_resolution)
        self.full_H_small = pixel_scale_homography(1 / scale, 1 / scale)
        self.small_H_full = np.linalg.inv(self.full_H_small)
        self.full_H_refine = pixel_scale_homography(1 / self.refine_scale, 1 / self.refine_scale)
        self.refine_H_full = np.linalg.inv(self.full_H_refine)
        side = int(REFINE_WINDOW_FLOW_PX * self.refine_scale / scale) // 2 * 2 + 1
        self.refine_window = (side, side)
        self.refine_levels = REFINE_LEVELS_FLOW_SCALE if self.refine_scale == scale else REFINE_LEVELS_FINE

    def reduce(self, image: np.ndarray) -> TrackImages:
        """(H, W, 3) BGR or (H, W) grey full image -> its :class:`TrackImages`."""
        gray = to_gray(image)
        refine = resize(gray, self.refine_scale)
        if self.refine_scale == self.scale:
            return TrackImages(refine, refine)
        # From the refinement image, not the full one: a 2x INTER_AREA is a fast path of OpenCV (0.1 ms for 1080p
        # against 1.5 ms for 4x), and the second halving costs 0.04 ms.
        return TrackImages(resize(refine, self.scale / self.refine_scale, scaled_size(gray.shape, self.scale)), refine)

    def anchor(
        self,
        images: TrackImages,
        camera: Camera,
        ref_H_img: np.ndarray,
        chain: str,
        inliers: int,
        area,
        margin_m: float,
        boxes,
    ) -> FlowStart:
        """Start a chain at a fully registered frame: its ``images``, the camera its registration implies (full
        resolution) and the scene ground (``area`` grown by ``margin_m``, not behind ``boxes``). Corners are
        detected in the flow image."""
        found = cv2.goodFeaturesToTrack(images.flow, self.max_corners, CORNER_QUALITY, CORNER_MIN_DISTANCE)
        xy = np.zeros((0, 2), np.float32) if found is None else found.reshape(-1, 2)
        full = apply_homography(self.full_H_small, xy)
        keep = ground_pixels(camera, full, area, margin_m, boxes)
        corners = xy[keep].reshape(-1, 1, 2).astype(np.float32)
        refine = apply_homography(self.refine_H_full, full[keep]).reshape(-1, 1, 2).astype(np.float32)
        anchor = Anchor(images, refine, ref_H_img, chain, inliers)
        return FlowStart(anchor, images, corners, np.eye(3))

    def step(self, state: FlowStart, images: TrackImages) -> FlowStep:
        """Register the frame of ``images`` from ``state`` (flow, then refinement against the anchor)."""

        def failed(reason, prev_H_cur=None, tracked=0):
            return FlowStep(None, prev_H_cur, tracked, 0, float('nan'), None, reason)

        if images.flow.shape != state.images.flow.shape:
            return failed(f'image size changed from {state.images.flow.shape} to {images.flow.shape}')
        if len(state.corners) < 4:
            return failed(f'only {len(state.corners)} ground corners in the previous frame')
        F, S = self.full_H_small, self.small_H_full
        guess = None
        if state.prev_H_cur is not None:  # constant motion: start where the last step would take the corners
            guess = cv2.perspectiveTransform(state.corners, S @ np.linalg.inv(state.prev_H_cur) @ F)
        cur, good = _track(
            state.images.flow, images.flow, state.corners, guess, FLOW_WINDOW, FLOW_LEVELS, FLOW_BACKWARD_CHECK
        )
        flow = fit_homography(
            apply_homography(F, cur.reshape(-1, 2)[good]),
            apply_homography(F, state.corners.reshape(-1, 2)[good]),
            self.estimator,
            self.threshold_px,
            seed=self.seed,
        )
        if flow.H is None:
            return failed(f'flow: {flow.reason}', tracked=int(good.sum()))
        predicted = state.anchor_H_img @ flow.H
        for _ in range(REFINE_PASSES):
            fit, good, xy_cur, moved = self._refine(state.anchor, images.refine, predicted)
            if fit.H is None:
                return failed(f'refinement against the anchor: {fit.reason}', flow.H, int(good.sum()))
            predicted = fit.H
            if moved <= REFINE_CONVERGED_PX:
                break
        corners = apply_homography(S, xy_cur[fit.inliers]).reshape(-1, 1, 2).astype(np.float32)
        return FlowStep(fit.H, flow.H, int(good.sum()), int(fit.inliers.sum()), fit.error_px, corners)

    def _refine(self, anchor: Anchor, refine: np.ndarray, predicted: np.ndarray) -> tuple:
        """One refinement pass: the current refinement image ``refine`` warped into the anchor by ``predicted``
        (current -> anchor, full resolution), the anchor's corners tracked into it and ``anchor_H_cur`` fitted.
        Returns (fit, (N,) bool corners tracked, (n, 2) their current full-resolution positions, median
        full-resolution px motion of the inliers in the warped image: how far ``predicted`` was off)."""
        F, S = self.full_H_refine, self.refine_H_full
        target = anchor.images.refine
        warped = cv2.warpPerspective(refine, S @ predicted @ F, target.shape[::-1], flags=cv2.INTER_LINEAR)
        found, good = _track(
            target, warped, anchor.corners, anchor.corners.copy(), self.refine_window, self.refine_levels
        )
        xy_cur = apply_homography(np.linalg.inv(predicted) @ F, found.reshape(-1, 2)[good])
        fit = fit_homography(
            xy_cur,
            apply_homography(F, anchor.corners.reshape(-1, 2)[good]),
            self.estimator,
            REFINE_THRESHOLD_PX,
            seed=self.seed,
        )
        motion = np.linalg.norm((found - anchor.corners).reshape(-1, 2)[good], axis=1) / self.refine_scale
        moved = float(np.median(motion[fit.inliers])) if fit.H is not None and fit.inliers.any() else float('inf')
        return fit, good, xy_cur, moved


def registered_camera(reference: Camera, implied: ImpliedCamera) -> Camera:
    """The full-resolution camera (the reference's intrinsics, size) a registration implies (the gate's
    :class:`ImpliedCamera`), for the ground mask of that frame's corners."""
    return Camera(reference.K, pose_matrix(implied.R, implied.t), reference.width, reference.height)
