"""Evaluation of a trained model on one sequence: detections -> tracker -> all metrics (+ PNGs)."""

from dataclasses import dataclass, field

import numpy as np

from matrix_core.bev.data import ground_truth_positions
from matrix_core.bev.inference import run_frames
from matrix_core.metrics import BevPoints, detection_metrics, hota_metrics, tracking_metrics
from matrix_core.tracking import BevDetections, BevTracker, TrackerSettings


@dataclass
class EvaluationResult:
    detection: object  # DetectionMetrics
    tracking: object  # TrackingMetrics
    gt: BevPoints
    detections: BevPoints
    tracks: BevPoints
    outputs: list  # FrameOutput per scored frame
    track_detections: BevPoints = None  # the tracks at their detection of each frame (image boxes)
    failed_frames: dict = field(default_factory=dict)  # frame -> why it was not scored
    masked_views: dict = field(default_factory=dict)  # (view, frame) -> why that view was masked there
    hota: object = None  # HotaMetrics of the tracks

    @property
    def scored_frames(self) -> list:
        return [o.frame for o in self.outputs]

    def failures_dict(self) -> dict:
        """JSON-ready account of what did not run: counts, then each failed frame and masked view with its
        reason (``metrics.json``'s ``failures``)."""
        return {
            'frames_failed': len(self.failed_frames),
            'frames_scored': len(self.outputs),
            'views_masked': len(self.masked_views),
            'failed_frames': [{'frame': f, 'reason': r} for f, r in sorted(self.failed_frames.items())],
            'masked_views': [
                {'view': v, 'frame': f, 'reason': r}
                for (v, f), r in sorted(self.masked_views.items(), key=lambda kv: kv[0][::-1])
            ],
        }

    def failures_text(self) -> str:
        """One line per failed frame and masked view, after a count line ('' when nothing failed)."""
        if not self.failed_frames and not self.masked_views:
            return ''
        lines = [
            f'{len(self.failed_frames)} frame(s) failed (not scored: metrics over {len(self.outputs)} '
            f'frames), {len(self.masked_views)} view(s) masked:'
        ]
        lines += [f'  frame {f}: {r}' for f, r in sorted(self.failed_frames.items())]
        lines += [
            f'  {v} frame {f}: {r}' for (v, f), r in sorted(self.masked_views.items(), key=lambda kv: kv[0][::-1])
        ]
        return '\n'.join(lines)


def ground_truth_points(frames_data, failures: dict = None) -> BevPoints:
    """``frame id x y`` ground truth of every frame of a BevFrames, restricted to the grid. A frame whose
    ground truth cannot be read is left out, its reason in ``failures`` (frame -> text; without it the error
    propagates)."""
    frames, ids, xy = [], [], []
    for f in frames_data.frames:
        try:
            positions = ground_truth_positions(frames_data.dataset, f)
        except Exception as exc:
            if failures is None:
                raise
            failures[f] = f'ground truth: {type(exc).__name__}: {exc}'
            continue
        for pid, p in positions.items():
            if frames_data.grid.contains(p)[0]:
                frames.append(f)
                ids.append(pid)
                xy.append(p)
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def evaluate(
    model,
    frames_data,
    tracker_settings: TrackerSettings = None,
    threshold: float = 0.5,
    gate: float = 1.0,
    progress: bool = True,
) -> EvaluationResult:
    """Run the model over ``frames_data`` (a BevFrames), track, and score against the ground truth.

    No frame ends the run: a frame whose ground truth, inputs or model step raises is not scored (neither
    its detections nor its ground truth count) and is listed in ``failed_frames``; the tracker still sees it
    as a frame without detections, so its clock stays the sequence's. Views masked for a bad image or
    calibration are listed in ``masked_views`` (``BevFrames.failures``)."""
    failed = {}
    gt = ground_truth_points(frames_data, failed)
    outputs = [o for o in run_frames(model, frames_data, progress, failed) if o.frame not in failed]
    return track_and_score(
        frames_data.frames,
        outputs,
        gt,
        tracker_settings,
        threshold,
        gate,
        failed,
        dict(getattr(frames_data, 'failures', {})),
    )


def track_and_score(
    frames: list,
    outputs: list,
    gt: BevPoints,
    tracker_settings: TrackerSettings = None,
    threshold: float = 0.5,
    gate: float = 1.0,
    failed: dict = None,
    masked_views: dict = None,
) -> EvaluationResult:
    """Track the model's per-frame ``outputs`` (:class:`FrameOutput`, the scored frames) over the sequence's
    ``frames`` and score detections and tracks against ``gt`` (only its scored frames count). A frame of
    ``frames`` without an output is a frame without detections for the tracker. Kept apart from inference so
    that tracker settings can be compared on one inference run (scripts/tune_tracker.py)."""
    by_frame = {o.frame: o for o in outputs}
    tracker = BevTracker(tracker_settings or TrackerSettings())
    d_frames, d_xy, d_scores = [], [], []
    t_frames, t_ids, t_xy, t_scores, t_det_xy = [], [], [], [], []
    for frame in frames:
        o = by_frame.get(frame)
        if o is None:
            tracker.update(BevDetections(np.zeros((0, 2)), np.zeros(0)))  # a frame without detections
            continue
        dets = o.detections
        d_frames += [o.frame] * len(dets)
        d_xy.append(dets.xy)
        d_scores.append(dets.scores)
        for t in tracker.update(dets):
            t_frames.append(o.frame)
            t_ids.append(t.track_id)
            t_xy.append(t.xy)
            t_scores.append(t.score)
            t_det_xy.append(t.detection_xy)
    dets = BevPoints(
        d_frames,
        np.concatenate(d_xy) if d_xy else np.zeros((0, 2)),
        scores=np.concatenate(d_scores) if d_scores else np.zeros(0),
    )
    tracks = BevPoints(t_frames, np.reshape(t_xy, (-1, 2)), ids=t_ids, scores=t_scores)
    keep = np.isin(gt.frames, list(by_frame))  # ground truth of the frames that were scored
    gt = BevPoints(gt.frames[keep], gt.xy[keep], ids=gt.ids[keep])
    return EvaluationResult(
        detection_metrics(gt, dets, threshold),
        tracking_metrics(gt, tracks, gate),
        gt,
        dets,
        tracks,
        outputs,
        BevPoints(t_frames, np.reshape(t_det_xy, (-1, 2)), ids=t_ids, scores=t_scores),
        dict(sorted((failed or {}).items())),
        dict(masked_views or {}),
        hota_metrics(gt, tracks, gate),
    )
