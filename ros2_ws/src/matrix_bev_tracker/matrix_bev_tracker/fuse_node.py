"""``fuse``: fuses N drones' images in the bird's-eye view, detects and tracks people, publishes the result.

Per view ``V`` in ``views`` it subscribes the image (``image_topic`` sensor_msgs/Image and/or
``compressed_topic`` CompressedImage, see ``image_kind``) and the frame's ground homography: with
``input_kind=homography`` ``homography_topic`` (matrix_msgs/HomographyStamped from ``register``; a status
other than ``ok`` or a confidence below ``min_confidence`` makes the view missing), with
``input_kind=camera_info`` ``camera_info_topic`` (CameraInfo, ``p = K [R | t]``, from ``calib`` or a bag's
ground truth). A view's images are subscribed once its geometry stream has a matched publisher
(``matrix_ros.connect``: no frame's geometry is lost at start-up). Messages are grouped by header stamp (matrix_core.sync.FrameSynchronizer); a frame is fused
when every view arrived or ``sync_timeout`` wall-clock seconds after its first message, with the views
that did arrive (a stopped drone never stalls the graph). The core is matrix_core.fusion.fuser.BevFuser.

Publishes, every fused frame (header.stamp = the frame's stamp, frame_id ``world_frame``):
- ``tracks_topic`` (matrix_msgs/TrackArray): confirmed tracks matched in this frame;
- ``detections_topic`` (matrix_msgs/TrackArray): every detection, id 0 (no identity), score, velocity from
  the network's tracking offset;
- ``markers_topic`` (visualization_msgs/MarkerArray): a cylinder and a text id per track (RViz);
- ``heatmap_topic`` (nav_msgs/OccupancyGrid): centre heatmap, 0-100 = score; -1 when no view was usable;
- ``/diagnostics`` (diagnostic_msgs/DiagnosticArray): per view availability + reason + registration
  confidence; summary with processing time, end-to-end latency (node clock - stamp; follows /clock under
  use_sim_time), wait (wall seconds from the frame's first message to publishing), resets, late messages.
Bad input (corrupt image, wrong encoding, NaN homography) is logged and the view counts as missing.
Service ``~/reset`` (std_srvs/Trigger) forgets pending frames, tracks and temporal features (start fresh); the
node does the same by itself when stamps go back by more than ``tracker_reset_gap_s`` (a replay restarted).
On SIGINT/SIGTERM it logs what it published and exits cleanly.
"""

import array
import time
from dataclasses import dataclass, field

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from matrix_msgs.msg import HomographyStamped, Track, TrackArray
from nav_msgs.msg import OccupancyGrid
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import Header
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

from matrix_core.fusion.fuser import BevFuser, FuseResult, ViewStatus
from matrix_core.fusion.settings import FuseSettings
from matrix_core.fusion.views import (ViewInput, ViewInputError, at_reduced_resolution, img_H_ground_from_projection,
                                      img_H_ground_from_registration, jpeg_reduction)
from matrix_core.sync import FrameSynchronizer, FrameSyncSettings
from matrix_core.tracking import BevDetections
from matrix_ros.connect import SubscribeWhenConnected
from matrix_ros.conversions import (ConversionError, compressed_to_image, is_jpeg, msg_to_image,
                                    seconds_to_stamp, stamp_to_seconds)
from matrix_ros.params import declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name


@dataclass
class FuseNodeSettings(FuseSettings):
    """The fusion settings (matrix_core.fusion.settings, incl. the tracker's) plus the node's outputs."""

    tracks_topic: str = field(default='/tracks', metadata={'help': 'matrix_msgs/TrackArray of the tracks'})
    detections_topic: str = field(default='/detections', metadata={
        'help': 'matrix_msgs/TrackArray of the detections (id 0)'})
    markers_topic: str = field(default='/markers', metadata={'help': 'visualization_msgs/MarkerArray of the tracks'})
    heatmap_topic: str = field(default='/bev_heatmap', metadata={'help': 'nav_msgs/OccupancyGrid heatmap ("" = off)'})
    world_frame: str = field(default='world', metadata={'help': 'frame_id of everything published'})
    qos: str = field(default='reliable', metadata={'help': 'QoS of the image subscriptions: reliable or sensor_data'})
    stamp_tolerance: float = field(default=0.001, metadata={'help': 'stamps closer than this (s) are one frame'})
    jpeg_reduced_decode: bool = field(default=True, metadata={
        'help': 'decode JPEG images directly at 1/2, 1/4 or 1/8 size when that still covers the network input '
                '(1920x1080 -> 960x540 for 480x272): about 0.1 s less per frame of 8 views; pixels differ from a '
                'full decode + resize by < 1 grey level'})

    def __post_init__(self):
        super().__post_init__()
        qos_by_name(self.qos)


def _stamp(msg) -> float:
    return stamp_to_seconds(msg.header.stamp)


class FuseNode(Node):
    def __init__(self, defaults: FuseNodeSettings):
        super().__init__('fuse')
        self.settings = s = declare_settings(self, FuseNodeSettings, defaults)
        self.fuser = BevFuser(s)
        self.frames_published = 0
        self.full_size = {}   # view -> (w, h) of its last fully decoded image
        self._start_fresh()
        self.connections = {v: self._subscribe_view(v) for v in s.views}
        out = publisher_qos()
        self.tracks_pub = self.create_publisher(TrackArray, s.tracks_topic, out)
        self.dets_pub = self.create_publisher(TrackArray, s.detections_topic, out)
        self.markers_pub = self.create_publisher(MarkerArray, s.markers_topic, out)
        self.heatmap_pub = self.create_publisher(OccupancyGrid, s.heatmap_topic, out) if s.heatmap_topic else None
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', out)
        self.create_service(Trigger, '~/reset', self._on_reset)
        # Sync timeouts run on the wall clock: under /clock in lockstep, sim time stops while the player waits.
        self.create_timer(0.05, self._poll, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'fusing {len(s.views)} views ({s.image_kind} images, {s.input_kind}) with {s.checkpoint_path()}; '
            f'grid {self.fuser.grid.shape} cells of {self.fuser.grid.cell} m; tracks on {s.tracks_topic}')

    def _subscribe_view(self, view: str) -> SubscribeWhenConnected:
        """The view's geometry now, its images once the geometry has a publisher (matrix_ros.connect)."""
        s = self.settings
        geometry_type, geometry_topic = ((HomographyStamped, s.homography_topic) if s.input_kind == 'homography'
                                         else (CameraInfo, s.camera_info_topic))
        geometry = self.create_subscription(geometry_type, s.topic(geometry_topic, view),
                                            lambda m: self._add(view, 'geometry', m, m), 10)

        def subscribe_images():
            qos = qos_by_name(s.qos)
            if s.image_kind in ('raw', 'both'):
                self.create_subscription(Image, s.topic(s.image_topic, view),
                                         lambda m: self._add(view, 'image', m, (msg_to_image, m)), qos)
            if s.image_kind in ('compressed', 'both'):
                self.create_subscription(CompressedImage, s.topic(s.compressed_topic, view),
                                         lambda m: self._add(view, 'image', m, (compressed_to_image, m)), qos)
        return SubscribeWhenConnected(self, view, [geometry], subscribe_images)

    def _start_fresh(self) -> None:
        """New synchroniser, no tracks, no temporal features."""
        s = self.settings
        streams = [f'{v}/{part}' for v in s.views for part in ('image', 'geometry')]
        self.sync = FrameSynchronizer(FrameSyncSettings(streams, s.sync_timeout, s.stamp_tolerance))
        self.first_arrival = {}   # stamp -> wall time of its first message
        self.late_reported = 0
        self.last_fused = None
        self.fuser.reset()

    # --- input -----------------------------------------------------------------------------------------
    def _add(self, view: str, part: str, msg, item) -> None:
        stamp, now = _stamp(msg), time.monotonic()
        if self.last_fused is not None and stamp < self.last_fused - self.settings.tracker_reset_gap_s:
            # A replay restarted or the clock jumped back: a new sequence, not late messages.
            self.get_logger().warning(f't={stamp:.3f} s is {self.last_fused - stamp:.1f} s before the last fused '
                                      f'frame: time went back, starting fresh')
            self._start_fresh()
        self.first_arrival.setdefault(round(stamp, 6), now)
        frames = self.sync.add(f'{view}/{part}', stamp, item, now)
        if self.sync.late_items > self.late_reported:
            self.late_reported = self.sync.late_items
            self.get_logger().warning(f'{view}: {part} at t={stamp:.3f} s arrived after its frame was fused; '
                                      f'ignored ({self.late_reported} late so far)', throttle_duration_sec=5.0)
        for frame in frames:
            self._fuse(frame)

    def _poll(self) -> None:
        for frame in self.sync.poll(time.monotonic()):
            self._fuse(frame)

    def _view_input(self, view: str, items: dict) -> ViewInput:
        """Decode one view's messages; any problem becomes the view's reason (logged)."""
        image_item, geo = items.get(f'{view}/image'), items.get(f'{view}/geometry')
        if image_item is None or geo is None:
            return ViewInput(reason='no ' + ' and no '.join(
                p for p, x in (('image', image_item), (self.settings.input_kind, geo)) if x is None))
        confidence = None
        try:
            if isinstance(geo, HomographyStamped):
                confidence = float(geo.confidence)
                if geo.status != 'ok':
                    raise ViewInputError(f'registration {geo.status}')
                if confidence < self.settings.min_confidence:
                    raise ViewInputError(f'registration confidence {confidence:.2f} < {self.settings.min_confidence}')
                H = img_H_ground_from_registration(geo.h_img_to_ground)
            else:
                H = img_H_ground_from_projection(geo.p)
            decode, msg = image_item
            image, H = self._decode(view, decode, msg, H)
        except (ViewInputError, ConversionError) as exc:
            self.get_logger().error(f'{view}: not used for this frame: {exc}')
            return ViewInput(reason=str(exc), confidence=confidence)
        return ViewInput(image, H, confidence=confidence)

    def _decode(self, view: str, decode, msg, img_H_ground):
        """The image and its ground homography: a JPEG at the smallest libjpeg scale that keeps the network
        input (``jpeg_reduced_decode``), once a full decode told the view's image size."""
        full = self.full_size.get(view)
        if isinstance(msg, CompressedImage) and self.settings.jpeg_reduced_decode and full and is_jpeg(msg):
            r = jpeg_reduction(full, self.fuser.input_size)
            if r > 1:
                image = compressed_to_image(msg, r)
                if (image.shape[1], image.shape[0]) == (-(-full[0] // r), -(-full[1] // r)):
                    return image, at_reduced_resolution(img_H_ground, r)
                # the stream's image size changed: decode in full and learn the new size
        image = decode(msg)
        self.full_size[view] = (image.shape[1], image.shape[0])
        return image, img_H_ground

    # --- fusion and output -----------------------------------------------------------------------------
    def _fuse(self, frame) -> None:
        s = self.settings
        t0 = time.perf_counter()
        views = {v: self._view_input(v, frame.items) for v in s.views}
        decode_s = time.perf_counter() - t0
        try:
            result = self.fuser.process(frame.stamp, views)
        except (ValueError, RuntimeError) as exc:   # e.g. non-finite network output: never invent detections
            self.get_logger().error(f't={frame.stamp:.3f} s: fusion failed, publishing no detections: {exc}')
            self.fuser.runner.reset()
            result = FuseResult(frame.stamp, BevDetections(np.zeros((0, 2)), np.zeros(0)), [], None,
                                {v: ViewStatus(False, f'fusion failed: {exc}') for v in s.views},
                                {'total_s': time.perf_counter() - t0 - decode_s}, ['temporal'])
        self.last_fused = frame.stamp
        result.timing = {'decode_s': decode_s, **result.timing}
        header = Header(stamp=seconds_to_stamp(frame.stamp), frame_id=s.world_frame)
        self.tracks_pub.publish(self._tracks_msg(header, result))
        self.dets_pub.publish(self._detections_msg(header, result.detections))
        self.markers_pub.publish(self._markers(header, result.tracks))
        if self.heatmap_pub is not None:
            self.heatmap_pub.publish(self._heatmap(header, result.heatmap))
        self.frames_published += 1
        first = self.first_arrival.pop(round(frame.stamp, 6), time.monotonic())
        for k in [k for k in self.first_arrival if k < frame.stamp]:   # frames the sync refused as late
            del self.first_arrival[k]
        result.timing['publish_s'] = time.perf_counter() - t0 - decode_s - result.timing['total_s']
        wait = time.monotonic() - first
        latency = self.get_clock().now().nanoseconds * 1e-9 - frame.stamp
        missing = [v for v, st in result.views.items() if not st.available]
        if missing:
            self.get_logger().warning(f't={frame.stamp:.3f} s: fused {len(s.views) - len(missing)}/{len(s.views)} '
                                      f'views ({frame.reason}); missing: ' + '; '.join(
                                          f'{v}: {result.views[v].reason}' for v in missing))
        if result.resets:
            self.get_logger().info(f't={frame.stamp:.3f} s: reset {" and ".join(result.resets)} state')
        self._diagnose(header, frame, result, wait, latency)

    def _tracks_msg(self, header, result) -> TrackArray:
        msg = TrackArray(header=header)
        for t in result.tracks:
            tr = Track(id=t.track_id, score=t.score, age=t.age, misses=t.misses)
            tr.position.x, tr.position.y = float(t.xy[0]), float(t.xy[1])
            tr.velocity.x, tr.velocity.y = float(t.velocity[0]), float(t.velocity[1])
            msg.tracks.append(tr)
        return msg

    def _detections_msg(self, header, dets) -> TrackArray:
        msg = TrackArray(header=header)
        period = self.settings.frame_interval_s
        for k in range(len(dets)):
            tr = Track(id=0, score=float(dets.scores[k]))
            tr.position.x, tr.position.y = float(dets.xy[k, 0]), float(dets.xy[k, 1])
            if dets.offsets is not None:   # offset points to the previous frame's position
                tr.velocity.x, tr.velocity.y = (float(-dets.offsets[k, i] / period) for i in range(2))
            msg.tracks.append(tr)
        return msg

    def _markers(self, header, tracks) -> MarkerArray:
        out = MarkerArray(markers=[Marker(header=header, action=Marker.DELETEALL)])
        for t in tracks:
            body = Marker(header=header, ns='tracks', id=t.track_id, type=Marker.CYLINDER, action=Marker.ADD)
            body.pose.position.x, body.pose.position.y, body.pose.position.z = float(t.xy[0]), float(t.xy[1]), 0.9
            body.pose.orientation.w = 1.0
            body.scale.x = body.scale.y = 0.5
            body.scale.z = 1.8
            hue = (t.track_id * 0.618034) % 1.0   # distinct, stable colour per id
            body.color.r, body.color.g, body.color.b, body.color.a = hue, 1.0 - hue, 0.5, 0.8
            text = Marker(header=header, ns='track_ids', id=t.track_id, type=Marker.TEXT_VIEW_FACING,
                          action=Marker.ADD, text=str(t.track_id))
            text.pose.position.x, text.pose.position.y, text.pose.position.z = float(t.xy[0]), float(t.xy[1]), 2.2
            text.pose.orientation.w = 1.0
            text.scale.z = 0.6
            text.color.r = text.color.g = text.color.b = text.color.a = 1.0
            out.markers += [body, text]
        return out

    def _heatmap(self, header, heatmap) -> OccupancyGrid:
        grid = self.fuser.grid
        msg = OccupancyGrid(header=header)
        msg.info.map_load_time = header.stamp
        msg.info.resolution = float(grid.cell)
        msg.info.height, msg.info.width = grid.shape          # rows along world y, like the heatmap
        msg.info.origin.position.x, msg.info.origin.position.y = float(grid.x_min), float(grid.y_min)
        msg.info.origin.orientation.w = 1.0
        if heatmap is None:
            msg.data = array.array('b', [-1]) * (grid.nx * grid.ny)
        else:
            msg.data = array.array('b', np.clip(np.round(heatmap * 100), 0, 100).astype(np.int8).tobytes())
        return msg

    def _diagnose(self, header, frame, result, wait, latency) -> None:
        statuses = []
        for view, st in result.views.items():
            level = DiagnosticStatus.OK if st.available else DiagnosticStatus.WARN
            status = DiagnosticStatus(level=level, name=f'fuse/{view}', hardware_id=view,
                                      message='used' if st.available else f'missing: {st.reason}'[:250])
            status.values = [KeyValue(key='available', value=str(st.available)),
                             KeyValue(key='confidence', value='' if st.confidence is None else f'{st.confidence:.3f}')]
            statuses.append(status)
        used = len(result.available_views)
        level = DiagnosticStatus.OK if used == len(result.views) else (
            DiagnosticStatus.WARN if used else DiagnosticStatus.ERROR)
        summary = DiagnosticStatus(level=level, name='fuse', hardware_id='fuse',
                                   message=f'{used}/{len(result.views)} views, {len(result.tracks)} tracks')
        summary.values = [KeyValue(key=k, value=str(v)) for k, v in (
            ('stamp', f'{frame.stamp:.6f}'), ('sync', frame.reason), ('views_used', used),
            ('detections', len(result.detections)), ('tracks', len(result.tracks)),
            *((k, f'{v:.4f}') for k, v in result.timing.items()),
            ('wait_s', f'{wait:.4f}'), ('latency_s', f'{latency:.4f}'), ('resets', ','.join(result.resets)),
            ('late_messages', self.sync.late_items), ('frames_published', self.frames_published))]
        self.diag_pub.publish(DiagnosticArray(header=header, status=[summary, *statuses]))

    def _on_reset(self, request, response):
        self._start_fresh()
        self.get_logger().info('reset: pending frames, tracks and temporal features forgotten')
        response.success, response.message = True, 'fuse state reset'
        return response

    def close(self) -> None:
        self.get_logger().info(f'published {self.frames_published} frames; '
                               f'{len(self.sync.pending_stamps)} pending frames dropped at shutdown; '
                               f'{self.sync.late_items} late messages')


def main(argv=None) -> int:
    return spin_node(FuseNode, FuseNodeSettings, argv, description=__doc__, on_exit=FuseNode.close)


if __name__ == '__main__':
    raise SystemExit(main())
