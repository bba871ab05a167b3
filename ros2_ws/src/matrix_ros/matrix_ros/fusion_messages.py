"""The fuse node's outputs as messages: tracks, detections, RViz markers, the BEV heatmap and the per-frame
diagnostics (all stamped with the fused frame's header), and per drone the image boxes and their overlay."""

import array

import numpy as np
from matrix_msgs.msg import Detection2D, Detection2DArray, Track, TrackArray
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import CompressedImage
from visualization_msgs.msg import Marker, MarkerArray

from matrix_core.live_scene import track_rgb
from matrix_ros import diagnostics

PERSON_HEIGHT_M, PERSON_DIAMETER_M = 1.8, 0.5  # the RViz cylinder of a track


def tracks_msg(header, tracks) -> TrackArray:
    """matrix_core.tracking tracks -> TrackArray (id, score, age, misses, position, velocity)."""
    msg = TrackArray(header=header)
    for t in tracks:
        tr = Track(id=t.track_id, score=t.score, age=t.age, misses=t.misses)
        tr.position.x, tr.position.y = float(t.xy[0]), float(t.xy[1])
        tr.velocity.x, tr.velocity.y = float(t.velocity[0]), float(t.velocity[1])
        msg.tracks.append(tr)
    return msg


def detections_msg(header, dets, frame_interval_s: float) -> TrackArray:
    """BevDetections -> TrackArray with id 0 (no identity); velocity from the network's tracking offset,
    which points to the previous frame's position ``frame_interval_s`` earlier."""
    msg = TrackArray(header=header)
    for k in range(len(dets)):
        tr = Track(id=0, score=float(dets.scores[k]))
        tr.position.x, tr.position.y = float(dets.xy[k, 0]), float(dets.xy[k, 1])
        if dets.offsets is not None:
            tr.velocity.x, tr.velocity.y = (float(-dets.offsets[k, i] / frame_interval_s) for i in range(2))
        msg.tracks.append(tr)
    return msg


def detections_2d_msg(header, boxes) -> Detection2DArray:
    """matrix_core.fusion.image_boxes ImageBoxes of one drone -> Detection2DArray (header: the frame's stamp,
    the drone's optical frame)."""
    msg = Detection2DArray(header=header)
    for b in boxes:
        x0, y0, x1, y1 = (float(v) for v in b.box)
        msg.detections.append(
            Detection2D(
                id=int(b.track_id),
                score=float(b.score),
                x_min=x0,
                y_min=y0,
                x_max=x1,
                y_max=y1,
                distance_m=float(b.distance_m),
                occluded=bool(b.occluded),
            )
        )
    return msg


def overlay_msg(header, image, boxes, quality: int = 80) -> CompressedImage:
    """The drone's (H, W, 3) BGR image with ``boxes`` (ImageBoxes) and their ids drawn, as a JPEG."""
    from matrix_core.fusion.image_boxes import draw_image_boxes
    from matrix_core.message_fields import compressed_fields

    drawn = draw_image_boxes(image, [b.box for b in boxes], [b.track_id for b in boxes], [b.occluded for b in boxes])
    return CompressedImage(header=header, **compressed_fields(drawn, 'jpeg', quality))


def markers_msg(header, tracks) -> MarkerArray:
    """A cylinder and a text id per track (RViz); the first marker deletes the previous frame's."""
    out = MarkerArray(markers=[Marker(header=header, action=Marker.DELETEALL)])
    for t in tracks:
        body = Marker(header=header, ns='tracks', id=t.track_id, type=Marker.CYLINDER, action=Marker.ADD)
        body.pose.position.x, body.pose.position.y = float(t.xy[0]), float(t.xy[1])
        body.pose.position.z = PERSON_HEIGHT_M / 2
        body.pose.orientation.w = 1.0
        body.scale.x = body.scale.y = PERSON_DIAMETER_M
        body.scale.z = PERSON_HEIGHT_M
        (body.color.r, body.color.g, body.color.b), body.color.a = track_rgb(t.track_id), 0.8
        text = Marker(
            header=header,
            ns='track_ids',
            id=t.track_id,
            type=Marker.TEXT_VIEW_FACING,
            action=Marker.ADD,
            text=str(t.track_id),
        )
        text.pose.position.x, text.pose.position.y, text.pose.position.z = float(t.xy[0]), float(t.xy[1]), 2.2
        text.pose.orientation.w = 1.0
        text.scale.z = 0.6
        text.color.r = text.color.g = text.color.b = text.color.a = 1.0
        out.markers += [body, text]
    return out


def heatmap_msg(header, grid, heatmap) -> OccupancyGrid:
    """(ny, nx) centre heatmap in [0, 1] on ``grid`` (a BevGrid) -> OccupancyGrid 0-100; all -1 when None
    (no view was usable)."""
    msg = OccupancyGrid(header=header)
    msg.info.map_load_time = header.stamp
    msg.info.resolution = float(grid.cell)
    msg.info.height, msg.info.width = grid.shape  # rows along world y, like the heatmap
    msg.info.origin.position.x, msg.info.origin.position.y = float(grid.x_min), float(grid.y_min)
    msg.info.origin.orientation.w = 1.0
    if heatmap is None:
        msg.data = array.array('b', [-1]) * (grid.nx * grid.ny)
    else:
        msg.data = array.array('b', np.clip(np.round(heatmap * 100), 0, 100).astype(np.int8).tobytes())
    return msg


def missing_views_text(frame, result) -> str:
    """The log line of a frame fused without some views, naming each and why ('' when none is missing)."""
    missing = [v for v, st in result.views.items() if not st.available]
    return (
        f't={frame.stamp:.3f} s: fused {len(result.views) - len(missing)}/{len(result.views)} views '
        f'({frame.reason}); missing: ' + '; '.join(f'{v}: {result.views[v].reason}' for v in missing)
        if missing
        else ''
    )


def fuse_diagnostics(header, frame, result, wait_s: float, latency_s: float, late_messages: int, frames_published: int):
    """``fuse/<view>`` (used or missing and why, registration confidence) and a ``fuse`` summary (sync
    reason, counts, timings, wait, latency, resets, late messages) of one fused frame."""
    statuses = []
    for view, st in result.views.items():
        statuses.append(
            diagnostics.status(
                f'fuse/{view}',
                diagnostics.OK if st.available else diagnostics.WARN,
                'used' if st.available else f'missing: {st.reason}',
                {
                    'available': st.available,
                    'status': str(st.status),
                    'confidence': '' if st.confidence is None else f'{st.confidence:.3f}',
                },
                view,
            )
        )
    used = len(result.available_views)
    level = diagnostics.OK if used == len(result.views) else (diagnostics.WARN if used else diagnostics.ERROR)
    summary = diagnostics.status(
        'fuse',
        level,
        f'{used}/{len(result.views)} views, {len(result.tracks)} tracks',
        (
            ('stamp', f'{frame.stamp:.6f}'),
            ('sync', frame.reason),
            ('views_used', used),
            ('detections', len(result.detections)),
            ('tracks', len(result.tracks)),
            *((k, f'{v:.4f}') for k, v in result.timing.items()),
            ('wait_s', f'{wait_s:.4f}'),
            ('latency_s', f'{latency_s:.4f}'),
            ('resets', ','.join(result.resets)),
            ('late_messages', late_messages),
            ('frames_published', frames_published),
        ),
        'fuse',
    )
    return diagnostics.array(header, summary, *statuses)
