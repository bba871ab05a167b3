"""Evaluation of a trained model on one sequence: detections -> tracker -> all metrics (+ PNGs)."""

from dataclasses import dataclass

import numpy as np

from matrix_core.bev.data import ground_truth_positions
from matrix_core.bev.inference import run_frames
from matrix_core.metrics import BevPoints, detection_metrics, tracking_metrics
from matrix_core.tracking import BevTracker, TrackerSettings


@dataclass
class EvaluationResult:
    detection: object       # DetectionMetrics
    tracking: object        # TrackingMetrics
    gt: BevPoints
    detections: BevPoints
    tracks: BevPoints
    outputs: list           # FrameOutput per frame
    track_detections: BevPoints = None   # the tracks at their detection of each frame (image boxes)


def ground_truth_points(frames_data) -> BevPoints:
    """``frame id x y`` ground truth of every frame of a BevFrames, restricted to the grid."""
    frames, ids, xy = [], [], []
    for f in frames_data.frames:
        for pid, p in ground_truth_positions(frames_data.dataset, f).items():
            if frames_data.grid.contains(p)[0]:
                frames.append(f)
                ids.append(pid)
                xy.append(p)
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def evaluate(model, frames_data, tracker_settings: TrackerSettings = None, threshold: float = 0.5,
             gate: float = 1.0, progress: bool = True) -> EvaluationResult:
    """Run the model over ``frames_data`` (a BevFrames), track, and score against the ground truth."""
    outputs = run_frames(model, frames_data, progress)
    tracker = BevTracker(tracker_settings or TrackerSettings())
    d_frames, d_xy, d_scores = [], [], []
    t_frames, t_ids, t_xy, t_scores, t_det_xy = [], [], [], [], []
    for o in outputs:
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
    dets = BevPoints(d_frames, np.concatenate(d_xy) if d_xy else np.zeros((0, 2)),
                     scores=np.concatenate(d_scores) if d_scores else np.zeros(0))
    tracks = BevPoints(t_frames, np.reshape(t_xy, (-1, 2)), ids=t_ids, scores=t_scores)
    gt = ground_truth_points(frames_data)
    return EvaluationResult(detection_metrics(gt, dets, threshold), tracking_metrics(gt, tracks, gate), gt, dets,
                            tracks, outputs, BevPoints(t_frames, np.reshape(t_det_xy, (-1, 2)), ids=t_ids,
                                                       scores=t_scores))
