"""``fuse``: fuses N drones' images in the bird's-eye view, detects and tracks people, publishes the result.

Per view ``V`` in ``views``: the image (``image_topic`` Image and/or ``compressed_topic`` CompressedImage, see
``image_kind``) and the frame's geometry, ``homography_topic`` (register's registration; a failed or unusable one, or
a confidence below ``min_confidence``, makes the view missing) or ``camera_info_topic`` (CameraInfo ``p = K [R | t]``
from calib or a bag's ground truth), per ``input_kind``; relative patterns (``matrix_core.topics``); images once the
geometry has a publisher (``matrix_ros.connect``), the geometry with ``geometry_qos`` (default history: also what a
drone published before it matched this node). ``dropped_topic``: a drone's notice (std_msgs/Header) that
``link_sender`` did not send a frame stands in for its image. Messages are grouped by stamp (``matrix_core.sync``); a
frame is fused when every view arrived or ``sync_timeout`` wall seconds after its first message (a stopped drone never
stalls the graph), by ``matrix_core.fusion`` (``view_inputs``, ``fuser.BevFuser``). Every fused frame publishes
(``matrix_ros.fusion_messages``) tracks, detections (id 0), RViz markers (while subscribed), the BEV heatmap,
their vision_msgs twins and world -> area on ``/tf_static`` (``matrix_ros.standard_outputs``),
``/diagnostics`` and per drone the tracks' image boxes (``matrix_ros.image_outputs``; optionally an overlay). Bad
input is logged and the view counts as missing. ``~/reset`` (std_srvs/Trigger) starts fresh, as when stamps go back
by more than ``restart_gap_s`` (a replay restarted). Images are decoded as they arrive (``decode_early``).
"""

import time

from diagnostic_msgs.msg import DiagnosticArray
from matrix_msgs.msg import HomographyStamped, TrackArray
from nav_msgs.msg import OccupancyGrid
from rclpy.clock import Clock, ClockType
from sensor_msgs.msg import CameraInfo, CompressedImage, Image
from std_msgs.msg import Header
from std_srvs.srv import Trigger
from visualization_msgs.msg import MarkerArray

from matrix_bev_tracker.settings import LIVE_PARAMETERS, FuseNodeSettings
from matrix_core import topics
from matrix_core.fusion.fuser import BevFuser
from matrix_core.fusion.view_inputs import ImageNotSent, ViewInputs
from matrix_core.fusion.views import FrameStatus
from matrix_core.sync import FrameSynchronizer, FrameSyncSettings
from matrix_ros import fusion_messages as out
from matrix_ros.connect import SubscribeWhenConnected
from matrix_ros.image_outputs import ImageOutputs
from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.standard_outputs import StandardOutputs
from matrix_ros.qos import publisher_qos, qos_by_name


class FuseNode(SettingsNode):
    def __init__(self, defaults: FuseNodeSettings):
        super().__init__('fuse')
        self.settings = s = declare_settings(self, FuseNodeSettings, defaults, live=LIVE_PARAMETERS)
        self.fuser = BevFuser(s, log=self.get_logger().info)  # device auto: its choice in the log
        warm_up_s = self.fuser.warm_up()  # before subscribing: the first frame would pay for the network's kernels
        self.inputs, self.frames_published = (
            ViewInputs(self.fuser.input_size, s.min_confidence, s.jpeg_reduced_decode),
            0,
        )
        self._start_fresh()
        self.connections = {v: self._subscribe_view(v) for v in s.views}
        qos = publisher_qos()
        self.pubs = {
            'tracks': self.create_publisher(TrackArray, s.tracks_topic, qos),
            'detections': self.create_publisher(TrackArray, s.detections_topic, qos),
            'markers': self.create_publisher(MarkerArray, s.markers_topic, qos),
            'diagnostics': self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS_TOPIC, qos),
        }
        if s.heatmap_topic:
            self.pubs['heatmap'] = self.create_publisher(OccupancyGrid, s.heatmap_topic, qos)
        self.image_outputs = ImageOutputs(self, s)
        self.standard_outputs = StandardOutputs(self, s, self.fuser.bev_settings.area or s.area)
        self.create_service(Trigger, '~/reset', self._on_reset)
        # Sync timeouts run on the wall clock: under /clock in lockstep, sim time stops while the player waits.
        self.create_timer(0.05, self._poll, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(
            f'fusing {len(s.views)} views ({s.image_kind} images, {s.input_kind}) with {s.checkpoint_path()} (warm-up '
            f'{warm_up_s:.2f} s); grid {self.fuser.grid.shape} cells of {self.fuser.grid.cell} m; '
            f'tracks on {s.tracks_topic}'
        )

    def _subscribe_view(self, view: str) -> SubscribeWhenConnected:
        """The view's geometry now, its images once the geometry has a publisher (matrix_ros.connect)."""
        s = self.settings
        geometry_type, pattern = (
            (HomographyStamped, s.homography_topic)
            if s.input_kind == 'homography'
            else (CameraInfo, s.camera_info_topic)
        )
        geometry = self.create_subscription(
            geometry_type, s.topic(pattern, view), lambda m: self._add(view, 'geometry', m), qos_by_name(s.geometry_qos)
        )

        def subscribe_images():
            for kind, msg_type, image_pattern in (
                ('raw', Image, s.image_topic),
                ('compressed', CompressedImage, s.compressed_topic),
            ):
                if s.image_kind in (kind, 'both'):
                    self.create_subscription(
                        msg_type,
                        s.topic(image_pattern, view),
                        lambda m: self._add(view, 'image', m),
                        qos_by_name(s.qos),
                    )
            if s.dropped_topic:  # the drone's word that a frame's image will not come
                self.create_subscription(
                    Header,
                    s.topic(s.dropped_topic, view),
                    lambda m: self._add(view, 'image', ImageNotSent(m)),
                    qos_by_name('reliable'),
                )

        return SubscribeWhenConnected(self, view, [geometry], subscribe_images)

    def _start_fresh(self) -> None:
        """New synchroniser, no tracks, no temporal features."""
        s = self.settings
        streams = [f'{v}/{part}' for v in s.views for part in ('image', 'geometry')]
        self.sync = FrameSynchronizer(FrameSyncSettings(streams, s.sync_timeout, s.stamp_tolerance))
        self.late_reported = 0
        self.fuser.reset()

    def _add(self, view: str, part: str, msg) -> None:
        stamp, now = stamp_seconds(msg.header.stamp), time.monotonic()
        if self.fuser.restart.is_back(stamp):  # compared with the frames fused: a lagging drone is only late
            self.get_logger().warning(
                f't={stamp:.3f} s is {self.fuser.restart.newest - stamp:.1f} s before the last fused frame: '
                'time went back, starting fresh (a replay restarted: a new sequence)'
            )
            self._start_fresh()
        if part == 'image':  # decoded now, while the drones work on this frame, or after an earlier frame fused
            self.inputs.decode_early(view, msg, defer=self.sync.waiting_before(stamp))
        frames = self.sync.add(f'{view}/{part}', stamp, msg, now)
        if self.sync.late_items > self.late_reported:
            self.late_reported = self.sync.late_items
            self.get_logger().warning(
                f'{view}: {part} at t={stamp:.3f} s arrived after its frame was fused; '
                f'ignored ({self.late_reported} late so far)',
                throttle_duration_sec=5.0,
            )
        for frame in frames:
            self._fuse(frame)

    def _poll(self) -> None:
        for frame in self.sync.poll(time.monotonic()):
            self._fuse(frame)

    def _fuse(self, frame) -> None:
        s, t0 = self.settings, time.perf_counter()
        views = self.inputs.frame_views(frame.items, s.views, s.input_kind)
        if views is None:  # geometry_qos history (e.g. after a restart) without a single image
            self.get_logger().warning(
                f't={frame.stamp:.3f} s: geometry without any image (published before this node matched?); not fused',
                throttle_duration_sec=5.0,
            )
            return
        for v in [v for v, view in views.items() if view.status == FrameStatus.REJECTED]:
            self.get_logger().error(f'{v}: not used for this frame: {views[v].reason}')
        result = self.fuser.process_safely(frame.stamp, views, decode_s=time.perf_counter() - t0)
        failed = [st.reason for st in result.views.values() if st.status == FrameStatus.FUSION_FAILED]
        if failed:
            self.get_logger().error(f't={frame.stamp:.3f} s: fusion failed: {failed[0]}; publishing no detections')
        header = Header(stamp=seconds_to_stamp(frame.stamp), frame_id=s.world_frame)
        self.pubs['tracks'].publish(out.tracks_msg(header, result.tracks))
        self.pubs['detections'].publish(out.detections_msg(header, result.detections, s.frame_interval_s))
        self.standard_outputs.publish(header, result, s.frame_interval_s)
        if self.pubs['markers'].get_subscription_count():  # for RViz: ~50 messages a frame, ~12 ms of CPU
            self.pubs['markers'].publish(out.markers_msg(header, result.tracks))
        self.image_outputs.publish(header.stamp, frame, result.tracks)
        if 'heatmap' in self.pubs:
            self.pubs['heatmap'].publish(out.heatmap_msg(header, self.fuser.grid, result.heatmap))
        self.frames_published += 1
        result.timing['publish_s'] = time.perf_counter() - t0 - result.timing['decode_s'] - result.timing['total_s']
        latency = self.get_clock().now().nanoseconds * 1e-9 - frame.stamp
        if missing := out.missing_views_text(frame, result):
            self.get_logger().warning(missing)
        if result.resets:
            self.get_logger().info(f't={frame.stamp:.3f} s: reset {" and ".join(result.resets)} state')
        diagnostics = out.fuse_diagnostics(
            header,
            frame,
            result,
            time.monotonic() - frame.first_arrival,
            latency,
            self.sync.late_items,
            self.frames_published,
        )
        diagnostics.status.extend(self.image_outputs.statuses)  # views whose reference cannot be read
        self.pubs['diagnostics'].publish(diagnostics)
        self.inputs.decode_deferred()  # published: now the images of the next frames, and the next frame's share
        self.fuser.prepare_next()  # of this one (its latency is spared both)

    def _on_reset(self, request, response):
        self._start_fresh()
        self.get_logger().info('reset: pending frames, tracks and temporal features forgotten')
        response.success, response.message = True, 'fuse state reset'
        return response

    def close(self) -> None:
        self.get_logger().info(
            f'published {self.frames_published} frames; {len(self.sync.pending_stamps)} pending '
            f'frames dropped at shutdown; {self.sync.late_items} late messages'
        )


def main(argv=None) -> int:
    return spin_node(FuseNode, FuseNodeSettings, argv, description=__doc__, on_exit=FuseNode.close)


if __name__ == '__main__':
    raise SystemExit(main())
