"""Fusing one synchronised multi-view frame: network inputs exactly as ``bev.data.BevFrames`` builds them
(so live == offline), ``bev.inference.SequenceRunner`` (temporal features), then ``tracking.BevTracker``.
"""

import dataclasses
import time
from dataclasses import dataclass, field

import cv2
import numpy as np
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.data import prepare_image
from matrix_core.bev.inference import SequenceRunner
from matrix_core.bev.lifting import feat_H_grid
from matrix_core.device import resolve_device
from matrix_core.fusion.settings import FuseSettings
from matrix_core.fusion.views import FrameStatus, ViewInput, ViewInputError, check_image
from matrix_core.sync.stamp_restart import StampRestart
from matrix_core.tracking import BevDetections, BevTracker


@dataclass(frozen=True)
class TrackState:
    """A confirmed track reported this frame: id, (2,) metres, (2,) m/s, score, frames since birth,
    consecutive misses (> 0 only for a coasting track reported at its prediction) and (2,) the position of
    its detection this frame (``TrackOutput.detection_xy``)."""

    track_id: int
    xy: np.ndarray
    velocity: np.ndarray
    score: float
    age: int
    misses: int = 0
    detection_xy: np.ndarray = None


@dataclass
class ViewStatus:
    """Whether a view took part in a frame (:class:`FrameStatus`); ``reason`` says why not; ``confidence`` of
    its homography."""

    status: FrameStatus
    reason: str = ''
    confidence: float = None

    @property
    def available(self) -> bool:
        return self.status == FrameStatus.USED


@dataclass
class FuseResult:
    """Output of one frame. ``heatmap``: (R, Q) sigmoid scores on ``BevFuser.grid`` (None when no view was
    usable and the network did not run); ``timing``: seconds per stage; ``resets``: what was reset first."""

    stamp: float
    detections: BevDetections
    tracks: list
    heatmap: np.ndarray
    views: dict
    timing: dict
    resets: list = field(default_factory=list)

    @property
    def available_views(self) -> list:
        return [v for v, s in self.views.items() if s.available]


def network_grid(bev_settings, settings: FuseSettings):
    """The BEV grid the network runs on: the settings' ``area`` (a site's) plus the checkpoint's margin, in the
    checkpoint's cells. The network is convolutional over the grid (encoder per image, lifting, pooling over
    views, temporal and head convolutions), so the area may be any size; the cell may not: the detector learnt
    the size of people in cells of the checkpoint's ``cell_m``. Another cell is a ValueError naming the site,
    the checkpoint and both cells."""
    cell = float(bev_settings.cell_m)
    if abs(float(settings.cell_m) - cell) > 1e-9:
        site = getattr(settings, 'site', '')
        where = f'site {site}' if site else 'the settings'
        raise ValueError(
            f'{where}: BEV cell {settings.cell_m:g} m, but checkpoint {settings.checkpoint_path()} was trained on '
            f'cells of {cell:g} m; train a detector for this site (matrix-tracker train --site) or give a '
            f'checkpoint of {settings.cell_m:g} m cells'
        )
    return dataclasses.replace(bev_settings, area=list(settings.area)).grid()


class BevFuser:
    """Stateful fusion of a stream of frames (call :meth:`process` in stamp order).

    Args:
        settings: :class:`FuseSettings`.
        model, bev_settings: an already loaded model (tests); default: ``load_model(settings.checkpoint_path())``
            with the decoding overrides of ``settings``.
        log: where ``device`` ``auto`` says what it chose (``matrix_core.device.resolve_device``).

    The network runs on ``settings.device``; each frame's images are prepared on the CPU (decoded, resized,
    normalised) and copied to the device once, as one batch.
    """

    def __init__(self, settings: FuseSettings, model=None, bev_settings=None, log=None):
        self.settings = settings
        self.device = resolve_device(settings.device, *([log] if log else []))  # before any work
        torch.set_num_threads(settings.threads)
        cv2.setNumThreads(settings.threads)  # image decoding and resizing: no idle pool threads spinning
        if model is None:
            model, bev_settings = load_model(settings.checkpoint_path(), settings.decode_overrides())
        self.model, self.bev_settings = model.to(self.device).eval(), bev_settings
        self.grid = network_grid(bev_settings, settings)
        self.input_size = (bev_settings.image_width, bev_settings.image_height)
        self.runner = SequenceRunner(self.model, bev_settings, self.grid)
        self.tracker = BevTracker(settings.tracker_settings())
        self._temporal_lost = False  # prepare_next failed: the next frame reports the temporal reset
        self.restart = StampRestart(settings.restart_gap_s)  # fed the stamps of the frames processed
        self.reset()

    def warm_up(self) -> float:
        """Run the network once on zeros (``FrameNetwork.warm_up``), so that a live graph's first frames do not
        pay for building its kernels; the fusion's state is unchanged. Returns the seconds it took."""
        t0 = time.perf_counter()
        self.runner.network.warm_up(len(self.settings.views), self.input_size)
        return time.perf_counter() - t0

    def prepare_next(self) -> None:
        """Compute now what the next frame needs of the last one (``SequenceRunner.prepare_next``): a live node
        calls it after publishing a frame, in time that would otherwise lie between its results and the next
        frame's. Without it the next :meth:`process` computes the same (the results do not change). An error here
        restarts the temporal state, as one in :meth:`process_safely` does, and the next frame's ``resets`` say
        so."""
        try:
            self.runner.prepare_next()
        except (ValueError, RuntimeError):
            self.runner.reset()
            self._temporal_lost = True

    def reset(self) -> None:
        """Start fresh: no temporal features, no tracks (ids restart at 1)."""
        self.runner.reset()
        self.tracker.reset()
        self.last_stamp = None
        self.restart.forget()
        self.frame_count = 0
        self._born = {}  # track id -> frame count at birth

    def _resets(self, stamp: float) -> list:
        s = self.settings
        lost, self._temporal_lost = self._temporal_lost, False
        if self.last_stamp is None:
            return ['temporal'] if lost else []
        gap = stamp - self.last_stamp
        if self.restart.is_back(stamp) or gap > s.tracker_reset_gap_s:  # a new run, or frames lost for long
            self.reset()
            return ['temporal', 'tracker']
        if gap <= 0:
            raise ValueError(f'frame at t={stamp:.3f} s is not after the last one at t={self.last_stamp:.3f} s')
        if gap > s.temporal_reset_gap_s or lost:
            self.runner.reset()
            return ['temporal']
        return []

    def _view_tensors(self, view: ViewInput):
        """(3, h, w) image and (3, 3) feat_H_grid of one usable view, as BevFrames builds them."""
        image = check_image(view.image)
        size = (image.shape[1], image.shape[0])
        # the model's stride is its encoder's, the one BevFrames uses offline
        try:
            fh = feat_H_grid(view.img_H_ground, self.grid.ground_H_grid, size, self.input_size, self.model.stride)
        except np.linalg.LinAlgError as exc:
            raise ViewInputError(f'ground homography unusable: {exc}') from None
        if not np.all(np.isfinite(fh)):
            raise ViewInputError('ground homography gives a non-finite feature warp')
        prepared = view.network_image if view.network_image is not None else prepare_image(image, self.input_size)
        return prepared, fh

    def process(self, stamp: float, views: dict) -> FuseResult:
        """Fuse one frame. ``views``: view name -> :class:`ViewInput` (absent names count as missing).

        A view is used when it has an image and a finite, non-singular homography; otherwise it is masked
        out and its reason reported. With no usable view the network does not run (no invented detections);
        the tracker still advances so that tracks age consistently.
        """
        t0 = time.perf_counter()
        resets = self._resets(stamp)
        names = self.settings.views
        w, h = self.input_size
        images = np.zeros((len(names), 3, h, w), np.float32)
        # Missing views get an all-zero warp: no cell is "in front", so they contribute nothing (and no NaN).
        fhs = np.zeros((len(names), 3, 3), np.float64)
        mask = np.zeros(len(names), bool)
        status = {}
        for i, name in enumerate(names):
            view = views.get(name)
            if view is None:
                status[name] = ViewStatus(FrameStatus.MISSING, 'no message')
                continue
            if not view.usable:
                why = view.status if view.status != FrameStatus.USED else FrameStatus.MISSING
                status[name] = ViewStatus(why, view.reason or 'image or homography missing', view.confidence)
                continue
            try:
                images[i], fhs[i] = self._view_tensors(view)
            except ViewInputError as exc:
                status[name] = ViewStatus(FrameStatus.REJECTED, str(exc), view.confidence)
                continue
            mask[i] = True
            status[name] = ViewStatus(FrameStatus.USED, '', view.confidence)
        t1 = time.perf_counter()
        heatmap = None
        if mask.any():
            out = self.runner.step(
                self.frame_count,
                torch.from_numpy(images),
                torch.from_numpy(fhs.astype(np.float32)),
                torch.from_numpy(mask),
            )
            dets, heatmap = out.detections, out.heatmap
        else:
            self.runner.reset()  # the next frame has no valid previous features
            dets = BevDetections(np.zeros((0, 2)), np.zeros(0), np.zeros((0, 2)))
            if 'temporal' not in resets:
                resets.append('temporal')
        t2 = time.perf_counter()
        tracks = self._track(dets)
        t3 = time.perf_counter()
        self.last_stamp = stamp
        self.restart.note(stamp)
        self.frame_count += 1
        timing = {'prepare_s': t1 - t0, 'network_s': t2 - t1, 'track_s': t3 - t2, 'total_s': t3 - t0}
        return FuseResult(stamp, dets, tracks, heatmap, status, timing, resets)

    def process_safely(self, stamp: float, views: dict, decode_s: float = 0.0) -> FuseResult:
        """:meth:`process` for a live stream: an error of the network (e.g. non-finite output) gives a frame with
        no detections, every view reported ``FUSION_FAILED`` saying why (never invented detections), and the temporal
        state restarts. ``decode_s`` (seconds spent building ``views``) is added to the timings."""
        t0 = time.perf_counter()
        try:
            result = self.process(stamp, views)
        except (ValueError, RuntimeError) as exc:
            self.runner.reset()
            result = FuseResult(
                stamp,
                BevDetections(np.zeros((0, 2)), np.zeros(0)),
                [],
                None,
                {v: ViewStatus(FrameStatus.FUSION_FAILED, str(exc)) for v in self.settings.views},
                {'total_s': time.perf_counter() - t0},
                ['temporal'],
            )
        result.timing = {'decode_s': decode_s, **result.timing}
        return result

    def _track(self, dets: BevDetections) -> list:
        out = []
        for t in self.tracker.update(dets):
            born = self._born.setdefault(t.track_id, self.frame_count)
            out.append(
                TrackState(
                    int(t.track_id),
                    t.xy,
                    t.velocity,
                    float(t.score),
                    self.frame_count - born,
                    int(t.misses),
                    t.detection_xy,
                )
            )
        alive = {tr.track_id for tr in self.tracker.tracks if tr.confirmed}
        self._born = {k: v for k, v in self._born.items() if k in alive}
        return out
