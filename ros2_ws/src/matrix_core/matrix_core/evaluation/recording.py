"""Scoring what a live graph recorded (the ``recorder``'s bag and/or MOT text) against a sequence bag's
ground truth, with the same metrics as the offline ``evaluate``.

Frames: ``frame = round((stamp - start_time) / frame_period)`` for every stamped message, with the sequence
clock (:mod:`matrix_core.bags.clock`) stored in the sequence bag (the recorder's MOT text already holds frames
computed that way). Ground truth: ``/ground_truth/pedestrians`` (+ ids) of
the sequence bag. As offline, ground truth outside the fused BEV grid is ignored; the grid comes from
``area`` or, when the recording holds the fuse node's heatmap (nav_msgs/OccupancyGrid), from its bounds.
Recorded message types come from the definitions embedded in the bag (matrix_msgs needs no ROS install).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader

from matrix_core.bags import read_bag
from matrix_core import topics as bag_topics
from matrix_core.bags.clock import SequenceClock, read_sequence_clock
from matrix_core.message_fields import stamp_ns
from matrix_core.metrics import BevPoints, detection_metrics, hota_metrics, read_bev_points, tracking_metrics


@dataclass
class Recording:
    """What was recorded: ``tracks`` (BevPoints with ids, or None), ``detections`` (with scores, or None),
    ``track_frames`` (sorted frames that had a TrackArray, even an empty one; None from MOT text),
    ``area`` (x_min, y_min, x_max, y_max of the recorded heatmap grid, or None)."""

    tracks: BevPoints = None
    detections: BevPoints = None
    track_frames: list = None
    area: tuple = None


@dataclass
class RecordingScores:
    detection: object  # DetectionMetrics (of the detections, else of the tracks)
    tracking: object  # TrackingMetrics, or None without tracks
    detections_source: str  # 'detections' or 'tracks'
    gt: BevPoints
    recording: Recording
    hota: object = None  # HotaMetrics of the tracks, or None without tracks


def read_recording_bag(
    path,
    tracks_topic=bag_topics.graph_topic(bag_topics.TRACKS),
    detections_topic=bag_topics.graph_topic(bag_topics.DETECTIONS),
    clock: SequenceClock = None,
) -> Recording:
    """Tracks, detections and the heatmap grid bounds from a recorder bag (topics missing -> None).

    Args:
        clock: numbers the frames (pass the sequence bag's); default: the clock the recorder stored.
    """
    clock = clock or read_sequence_clock(path)
    tracks, dets = ([], [], [], []), ([], [], [])
    track_frames, area = set(), None
    with AnyReader([Path(path)]) as reader:
        topics = {c.topic: c.msgtype for c in reader.connections}
        for topic in (tracks_topic, detections_topic):
            if topic in topics and topics[topic] != bag_topics.TRACK_ARRAY_TYPE:
                raise ValueError(f'{path}: {topic} is {topics[topic]}, expected {bag_topics.TRACK_ARRAY_TYPE}')
        for conn, _, raw in reader.messages(connections=reader.connections):
            if conn.msgtype not in (bag_topics.TRACK_ARRAY_TYPE, bag_topics.OCCUPANCY_GRID_TYPE):
                continue
            msg = reader.deserialize(raw, conn.msgtype)
            frame = clock.frame_ns(stamp_ns(msg.header))
            if conn.msgtype == bag_topics.OCCUPANCY_GRID_TYPE:
                i = msg.info
                x0, y0 = i.origin.position.x, i.origin.position.y
                area = (x0, y0, x0 + i.width * i.resolution, y0 + i.height * i.resolution)
            elif conn.topic == tracks_topic:
                track_frames.add(frame)
                for t in msg.tracks:
                    for col, v in zip(tracks, (frame, t.id, t.position.x, t.position.y)):
                        col.append(v)
            elif conn.topic == detections_topic:
                for t in msg.tracks:
                    for col, v in zip(dets, (frame, (t.position.x, t.position.y), t.score)):
                        col.append(v)
        has_tracks, has_dets = tracks_topic in topics, detections_topic in topics
    if not (has_tracks or has_dets):
        raise ValueError(
            f'{path}: neither {tracks_topic} nor {detections_topic} was recorded (topics: {sorted(topics)})'
        )
    return Recording(
        BevPoints(tracks[0], np.column_stack([tracks[2], tracks[3]]) if tracks[0] else np.zeros((0, 2)), ids=tracks[1])
        if has_tracks
        else None,
        BevPoints(dets[0], np.reshape(dets[1], (-1, 2)), scores=dets[2]) if has_dets else None,
        sorted(track_frames) if has_tracks else None,
        area,
    )


def read_recording(path, **kwargs) -> Recording:
    """A recorder bag folder, or a MOT text file ``frame id x y`` (tracks only)."""
    path = Path(path)
    if (path / 'metadata.yaml').is_file():
        return read_recording_bag(path, **kwargs)
    if path.is_file():
        return Recording(tracks=read_bev_points(path, with_ids=True))
    raise FileNotFoundError(f'{path}: neither a rosbag2 folder nor a MOT text file')


def has_ground_truth(path) -> bool:
    """Whether the bag at ``path`` records the people's ground truth (``/ground_truth/pedestrians``): a sequence
    bag does, a user's own recording (images and camera_info only) does not."""
    from matrix_core.bags.salvage import topic_counts

    return bag_topics.PEDESTRIANS_TOPIC in topic_counts(path)[0]


def ground_truth_from_bag(path, clock: SequenceClock = None) -> BevPoints:
    """``frame id x y`` of every person in a sequence bag's ``/ground_truth/pedestrians`` (+ ids); frames by
    ``clock`` (default: the one the bag stores)."""
    clock = clock or read_sequence_clock(path)
    poses, ids = {}, {}
    for bm in read_bag(path, [bag_topics.PEDESTRIANS_TOPIC, bag_topics.PEDESTRIAN_IDS_TOPIC]):
        if bm.topic == bag_topics.PEDESTRIANS_TOPIC:
            poses[bm.time_ns] = (stamp_ns(bm.msg.header), [(p.position.x, p.position.y) for p in bm.msg.poses])
        else:
            ids[bm.time_ns] = [int(i) for i in bm.msg.data]
    if not poses:
        raise ValueError(f'{path}: no {bag_topics.PEDESTRIANS_TOPIC} messages (not a sequence bag?)')
    frames, pids, xy = [], [], []
    for time_ns, (stamp, points) in sorted(poses.items()):
        frame_ids = ids.get(time_ns)
        if frame_ids is None or len(frame_ids) != len(points):
            raise ValueError(f'{path}: pedestrian ids missing or not matching the poses at t={stamp * 1e-9:.3f} s')
        frames += [clock.frame_ns(stamp)] * len(points)
        pids += frame_ids
        xy += points
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=pids)


def _select(points: BevPoints, keep: np.ndarray) -> BevPoints:
    return BevPoints(
        points.frames[keep],
        points.xy[keep],
        ids=None if points.ids is None else points.ids[keep],
        scores=points.scores[keep],
    )


def _inside(points: BevPoints, area) -> BevPoints:
    x0, y0, x1, y1 = area
    xy = points.xy
    return _select(points, (xy[:, 0] >= x0) & (xy[:, 0] < x1) & (xy[:, 1] >= y0) & (xy[:, 1] < y1))


def _in_frames(points: BevPoints, frames) -> BevPoints:
    return None if points is None else _select(points, (points.frames >= frames[0]) & (points.frames <= frames[1]))


def score_recording(
    recording: Recording, gt: BevPoints, area=None, frames=None, threshold: float = 0.5, gate: float = 1.0
) -> RecordingScores:
    """Detection metrics (of the detections when recorded, else of the tracks), tracking metrics and HOTA.

    Args:
        area: x_min y_min x_max y_max (m) where ground truth counts (default: the recorded heatmap grid,
            else everywhere).
        frames: (first, last) inclusive frame range to score (default: every ground-truth frame).
        threshold, gate: detection / tracking match distances (m), as offline.
    """
    area = area if area is not None else recording.area
    if area is not None:
        gt = _inside(gt, area)
    if frames is not None:
        gt = _in_frames(gt, frames)
        recording = Recording(
            _in_frames(recording.tracks, frames),
            _in_frames(recording.detections, frames),
            recording.track_frames,
            recording.area,
        )
    source = 'detections' if recording.detections is not None else 'tracks'
    det = detection_metrics(gt, recording.detections if source == 'detections' else recording.tracks, threshold)
    trk = tracking_metrics(gt, recording.tracks, gate) if recording.tracks is not None else None
    hota = hota_metrics(gt, recording.tracks, gate) if recording.tracks is not None else None
    return RecordingScores(det, trk, source, gt, recording, hota)
