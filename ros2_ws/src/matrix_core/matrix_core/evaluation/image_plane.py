"""Scoring the image-plane output (2D boxes with fused ids per drone) against a dataset's annotated boxes.

The tracks of a frame become boxes in each drone with :func:`matrix_core.fusion.image_boxes.image_boxes`
and that frame's camera of the drone; the annotated boxes are the dataset's ``PersonAnnotation.boxes``
(person ids), clipped to the image like the predictions. Metrics: :mod:`matrix_core.metrics.image_boxes`.
"""

from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np
from rosbags.highlevel import AnyReader

from matrix_core import topics
from matrix_core.message_fields import stamp_ns

from matrix_core.fusion.image_boxes import (
    ImageBoxSettings,
    camera_from_ground_homography,
    clip_box,
    draw_image_boxes,
    image_boxes,
    obstacles_from_meta,
)
from matrix_core.message_fields import image_from_msg
from matrix_core.metrics.image_boxes import FrameBoxes, per_view_metrics
from matrix_core.output_paths import atomic_path


@dataclass
class ImagePlaneScores:
    """Predicted and annotated boxes, and ``metrics``: drone -> TrackingMetrics, plus ``'all'``."""

    pred: FrameBoxes
    gt: FrameBoxes
    metrics: dict

    def as_dict(self) -> dict:
        return {v: m.as_dict() for v, m in self.metrics.items()}


def scene_box_settings(dataset, settings: ImageBoxSettings = None) -> ImageBoxSettings:
    """``settings`` with the dataset's own obstacle boxes when its meta states them (simulated folders)."""
    s = settings or ImageBoxSettings()
    return replace(s, obstacle_boxes=obstacles_from_meta(getattr(dataset, 'meta', None), s.obstacle_boxes))


def reference_intrinsics(dataset, view: str, frame: int) -> np.ndarray:
    """(3, 3) K of ``view``: its reference calibration's when the dataset has one (what the live graph's
    fuse node knows), else that frame's calibration's."""
    if getattr(dataset, 'has_reference', False):
        return dataset.reference_camera(view).K
    return dataset.camera(view, frame).K


def homography_cameras(dataset, homography_of):
    """``camera_of(view, frame)``: the camera implied by ``homography_of``'s (img_H_ground, (w, h))
    (``bev.calibration_sources``) with the view's :func:`reference_intrinsics`; None where it has none."""

    def camera_of(view, frame):
        h = homography_of(view, frame)
        return (
            None if h is None else camera_from_ground_homography(h[0], reference_intrinsics(dataset, view, frame), h[1])
        )

    return camera_of


def score_image_plane(
    dataset,
    tracks,
    camera_of,
    views,
    frames,
    settings: ImageBoxSettings = None,
    iou_threshold: float = 0.5,
    frame_numbers=None,
) -> ImagePlaneScores:
    """Boxes of ``tracks`` (BevPoints, frames numbered like ``frame_numbers``, default the dataset frames
    ``frames``) against the annotated boxes of ``frames`` in ``views``; the dataset's obstacles."""
    settings = scene_box_settings(dataset, settings)
    pred = predicted_boxes(tracks, camera_of, views, settings)
    gt = annotated_boxes(dataset, frames, views, frame_numbers)
    return ImagePlaneScores(pred, gt, per_view_metrics(gt, pred, iou_threshold))


def read_recorded_boxes(path, clock) -> FrameBoxes:
    """Every ``<view>/detections_2d`` (matrix_msgs/Detection2DArray) of a recorder bag; frames by ``clock``
    (the sequence clock); the view is the topic's drone ('/D3/detections_2d' -> 'D3')."""

    rows = ([], [], [], [], [])
    with AnyReader([Path(path)]) as reader:
        conns = [
            c
            for c in reader.connections
            if c.msgtype == topics.DETECTION_2D_ARRAY_TYPE and c.topic.endswith('/' + topics.DETECTIONS_2D)
        ]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            frame, view = clock.frame_ns(stamp_ns(msg.header)), conn.topic.split('/')[-2]
            for d in msg.detections:
                for col, val in zip(rows, (frame, view, d.id, (d.x_min, d.y_min, d.x_max, d.y_max), d.score)):
                    col.append(val)
    return FrameBoxes(rows[0], rows[1], rows[2], np.reshape(rows[3], (-1, 4)), rows[4])


def read_recorded_overlays(path, clock, frame: int) -> dict:
    """view -> (H, W, 3) BGR image of every ``<view>/overlay/compressed`` of a recorder bag at ``frame``."""

    images = {}
    with AnyReader([Path(path)]) as reader:
        conns = [c for c in reader.connections if c.topic.endswith('/' + topics.OVERLAY_COMPRESSED)]
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if clock.frame_ns(stamp_ns(msg.header)) == frame:
                images[conn.topic.strip('/').split('/')[-3]] = image_from_msg(msg)
    return dict(sorted(images.items()))


def ids_in_tracks(boxes: FrameBoxes, tracks) -> float:
    """Fraction of ``boxes`` whose id is a track id of the same frame in ``tracks`` (BevPoints with ids):
    1.0 when every drone's identities are the BEV track ids (NaN without boxes)."""
    known = set(zip(tracks.frames.tolist(), tracks.ids.tolist()))
    hits = [(int(f), int(i)) in known for f, i in zip(boxes.frames, boxes.ids)]
    return float(np.mean(hits)) if hits else float('nan')


def annotated_boxes(dataset, frames, views, frame_numbers=None) -> FrameBoxes:
    """Annotated boxes of ``frames`` (dataset frame numbers) in ``views``, clipped to the image; the output
    frame of ``frames[k]`` is ``frame_numbers[k]`` (default: the dataset frame itself)."""
    size = getattr(dataset, 'view_image_size', None)  # a site dataset's drones have cameras of their own
    sizes = {v: size(v) if size else dataset.image_size for v in views}
    rows = ([], [], [], [])
    for k, f in enumerate(frames):
        for person in dataset.annotations(f):
            for v, b in person.boxes.items():
                if v in views:
                    for col, val in zip(
                        rows,
                        (
                            (frame_numbers or frames)[k],
                            v,
                            person.person_id,
                            clip_box([b.xmin, b.ymin, b.xmax, b.ymax], *sizes[v]),
                        ),
                    ):
                        col.append(val)
    return FrameBoxes(rows[0], rows[1], rows[2], np.reshape(rows[3], (-1, 4)))


def predicted_boxes(tracks, camera_of, views, settings: ImageBoxSettings) -> FrameBoxes:
    """Boxes of ``tracks`` (BevPoints with ids and scores) in every view: ``camera_of(view, frame)`` gives the
    frame's Camera (None: the view has no camera that frame, no boxes)."""
    parts = []
    for f, rows in tracks.by_frame().items():
        for v in views:
            camera = camera_of(v, f)
            if camera is None:
                continue
            found = image_boxes(camera, tracks.ids[rows], tracks.xy[rows], tracks.scores[rows], settings)
            if found:
                parts.append(
                    FrameBoxes(
                        [f] * len(found),
                        [v] * len(found),
                        [b.track_id for b in found],
                        np.array([b.box for b in found]),
                        [b.score for b in found],
                    )
                )
    return FrameBoxes.concatenate(parts)


def draw_frame_png(path, images: dict, pred: FrameBoxes, gt: FrameBoxes, frame: int, title: str = '') -> None:
    """A mosaic (4 columns) of every drone's image of ``frame`` (view -> BGR image) with the annotated boxes
    (thin white) and the predicted boxes with their ids (colour per id)."""
    tiles = []
    for v, image in images.items():
        img = image.copy()
        for b in gt.boxes[(gt.frames == frame) & (gt.views == v)]:
            cv2.rectangle(
                img, tuple(int(round(c)) for c in b[:2]), tuple(int(round(c)) for c in b[2:]), (255, 255, 255), 2
            )
        sel = (pred.frames == frame) & (pred.views == v)
        img = draw_image_boxes(img, pred.boxes[sel], pred.ids[sel])
        cv2.putText(img, f'{v} frame {frame}', (20, 60), cv2.FONT_HERSHEY_SIMPLEX, 2.0, (0, 255, 255), 5)
        tiles.append(cv2.resize(img, (img.shape[1] // 3, img.shape[0] // 3), interpolation=cv2.INTER_AREA))
    if not tiles:
        return
    cols = min(4, len(tiles))
    blank = np.zeros_like(tiles[0])
    tiles += [blank] * (-len(tiles) % cols)
    mosaic = np.vstack([np.hstack(tiles[r : r + cols]) for r in range(0, len(tiles), cols)])
    if title:
        bar = np.zeros((50, mosaic.shape[1], 3), np.uint8)
        cv2.putText(bar, title, (10, 35), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2)
        mosaic = np.vstack([bar, mosaic])
    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), mosaic):
            raise OSError(f'cannot write {path}')
