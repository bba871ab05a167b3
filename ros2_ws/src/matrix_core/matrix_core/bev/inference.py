"""Running a trained model frame by frame over a sequence (temporal features carried over)."""

from dataclasses import dataclass

import numpy as np
import torch

from matrix_core.bev.decode import Peaks, find_peaks, peak_detections
from matrix_core.bev.frame_network import FrameNetwork


@dataclass
class FrameOutput:
    """Per-frame result: ``detections`` (BevDetections, world metres) and ``heatmap`` (R, Q) scores."""

    frame: int
    detections: object
    heatmap: np.ndarray


class SequenceRunner:
    """Feeds consecutive frames to the model, handing each frame's BEV features to the next. The model runs as a
    :class:`~matrix_core.bev.frame_network.FrameNetwork` (its outputs, less work; a snapshot of its weights).

    ``reset()`` forgets the previous frame (start of a new sequence or after a gap in the stream).

    The network and the peak finding run on the model's device; what leaves it per frame is the (R, Q) score map
    and the peaks' cells and head values (decoded to metres on the CPU).
    """

    def __init__(self, model, settings, grid):
        self.settings, self.grid = settings, grid
        self.network = FrameNetwork(model.eval(), grid.shape)
        self.reset()

    def reset(self) -> None:
        self.previous = None

    def prepare_next(self) -> None:
        """Compute now what the next step needs of the last (``FrameNetwork.prepare_next``): call it when idle."""
        if self.previous is not None:
            self.network.prepare_next(self.previous)

    @torch.no_grad()
    def step(self, frame: int, images, feat_H_grid, view_mask) -> FrameOutput:
        """One frame: ``images`` (V, 3, h, w), ``feat_H_grid`` (V, 3, 3), ``view_mask`` (V,) bool."""
        s = self.settings
        out = self.network(images, feat_H_grid, view_mask, self.previous)
        self.previous = out if s.temporal else None  # its carry computed on demand (or by prepare_next)
        peaks = find_peaks(out.heatmap, self.grid, s.score_threshold, s.nms_radius_m, s.max_detections)
        tracking, offset = self.network.heads_at(out.fused, peaks.rows, peaks.cols, offset=s.subcell == 'offset')
        peaks = Peaks(peaks.scores.cpu(), peaks.rows.cpu(), peaks.cols.cpu(), peaks.score.cpu())  # CPU: no copy
        dets = peak_detections(peaks, self.grid, tracking.cpu(), None if offset is None else offset.cpu(), s.subcell)
        return FrameOutput(frame, dets, peaks.scores.numpy())


def run_frames(model, frames_data, progress: bool = True, failures: dict = None) -> list:
    """:class:`FrameOutput` of every frame of a :class:`~matrix_core.bev.data.BevFrames`, in order.

    A frame whose inputs or model step raises is left out, its reason stored in ``failures`` (frame -> text;
    without it the error propagates), and the temporal features are reset: the next frame is never fused
    with features of a frame before the gap."""
    from tqdm import tqdm

    runner = SequenceRunner(model, frames_data.settings, frames_data.grid)
    out = []
    for frame in tqdm(frames_data.frames, desc='inference', unit='frame', disable=not progress, leave=False):
        try:
            x = frames_data.inputs(frame)
            out.append(runner.step(frame, x['images'], x['feat_H_grid'], x['view_mask']))
        except Exception as exc:
            if failures is None:
                raise
            failures[frame] = f'inference: {type(exc).__name__}: {exc}'
            runner.reset()
    return out
