"""``bag_player``: publish a rosbag2 (MCAP or SQLite) into the live graph, with ``/clock``.

Messages are published exactly as recorded (serialized bytes, no re-encoding) on their recorded topics, which
ROS remapping rules rename (``--ros-args -r /cam_front/image:=/alpha/image_raw``).
Messages with the same bag time form one frame. Two pacings:

- ``rate``: frames follow the recorded timing scaled by ``rate`` (2.0 = twice as fast);
- ``lockstep``: the next frame is published only after ``lockstep_count`` messages stamped with the
  current frame's time arrived on ``lockstep_topic`` (e.g. the fuse node's output), or after
  ``lockstep_timeout`` seconds (logged), so evaluation is deterministic whatever the machine's speed; with
  ``lockstep_window`` 2 once the frame before the current one is released (``matrix_ros.lockstep``).
  Before the first frame the player waits until ``lockstep_topic`` has a publisher; the lockstep
  subscription asks for ``lockstep_qos`` ``history`` (transient local), so an announcement published before
  the two sides matched still arrives (this workspace's publishers offer it, see ``matrix_ros.qos``).

The bag's sequence clock (``matrix_core.bags.clock``: first stamp and frame period, stored in its metadata)
numbers the frames in the log. ``/clock`` (rosgraph_msgs/Clock) carries the bag time of each frame before it
is published, so nodes started with ``use_sim_time:=true`` follow the recording. Published topics offer
transient-local history (``matrix_ros.qos.publisher_qos``). When all frames are out the node logs it and, with
``exit_when_done``, exits: code 0, or 3 when lockstep timed out for some frame (the run is not
deterministic), 4 when the bag is damaged (cut short, overwritten: the frames before the damage were played,
the error says where it stopped; ``matrix_core.bags.salvage``), 1 when nothing was played.
"""

import math
import time
from pathlib import Path

import rclpy
from rclpy.duration import Duration
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Header

from matrix_core.bags.clock import read_sequence_clock
from matrix_core.bags.salvage import BagDamaged, connections, raw_messages
from matrix_core.message_fields import stamp_seconds
from matrix_core.site.parameter import check_bag_drones, named_site
from matrix_ros.connect import SubscribersReady
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.executor import make_executor, spin_until
from matrix_ros.lockstep import LockstepWindow
from matrix_ros.message_types import message_class
from matrix_ros.params import SettingsNode, parse_node_args, declare_settings
from matrix_ros.player_settings import BagPlayerSettings
from matrix_ros.qos import publisher_qos, qos_by_name


class BagPlayer(SettingsNode):
    def __init__(self, defaults: BagPlayerSettings):
        super().__init__('bag_player')
        self.settings = s = declare_settings(self, BagPlayerSettings, defaults)
        if not (Path(s.bag) / 'metadata.yaml').is_file():
            raise FileNotFoundError(f'not a rosbag2 folder (no metadata.yaml): {s.bag}')
        self.sequence_clock = read_sequence_clock(s.bag, note=self.get_logger().warning)
        recorded = connections(s.bag)
        # another site's recording is refused before playing; the names as published (after -r FROM:=TO rules)
        check_bag_drones(named_site(s.site), [self.resolve_topic_name(t) for t in recorded], s.bag)
        self.topics = {t: msgtype for t, msgtype in recorded.items() if not s.topics or t in s.topics}
        self.damage = ''  # why the bag could not be played to its end ('' when it was)
        qos = publisher_qos(s.qos)
        self.pubs = {t: self.create_publisher(message_class(msgtype), t, qos) for t, msgtype in self.topics.items()}
        self.clock_pub = self.create_publisher(Clock, '/clock', 10)
        self.skipped = 0  # frames due (start_at) before the player was ready
        self.lockstep_sub, self.spinner = None, make_executor()
        self.spinner.add_node(self)
        self.lockstep = LockstepWindow(
            s.lockstep_window, s.lockstep_count, s.lockstep_timeout, self._spin_for, self.get_logger().warning
        )
        if s.lockstep:
            self.lockstep_sub = self.create_subscription(
                message_class(s.lockstep_type),
                s.lockstep_topic,
                self.lockstep.on_message,
                qos_by_name(s.lockstep_qos, 50),
            )
        self.get_logger().info(
            f'playing {s.bag}: {len(self.pubs)} topics, '
            + (f'lockstep on {s.lockstep_topic}' if s.lockstep else f'rate {s.rate}')
            + f'; sequence clock: {self.sequence_clock.describe()}'
        )

    def _spin_for(self, seconds: float, until=lambda: False):
        deadline = time.monotonic() + seconds
        while rclpy.ok() and time.monotonic() < deadline and not until():
            self.spinner.spin_once(timeout_sec=min(0.05, max(0.0, deadline - time.monotonic())))

    def _start_time(self, topic: str) -> float:
        """The wall time the first frame is due: the stamp of the first Header on ``topic`` (0 if stopped first).
        The subscription is made now, once ready (its match is what says so), and kept: destroying an entity
        under rclpy's EventsExecutor is what its shutdown was once seen to hang on."""
        got = []
        self.start_sub = self.create_subscription(
            Header, topic, lambda msg: got.append(stamp_seconds(msg.stamp)), qos_by_name('history', 1)
        )
        self.get_logger().info(f'ready; waiting for the start time on {topic}')
        self._spin_for(math.inf, lambda: bool(got))
        return got[0] if got else 0.0

    def frames(self):
        """Yield (bag time ns, [(topic, raw bytes)]) grouped by identical bag time. A damaged bag ends with
        the last whole frame before the damage (the one it cut is not played), the reason in ``damage``."""
        group, group_time = [], None
        try:
            for topic, _, time_ns, raw in raw_messages(self.settings.bag, set(self.topics)):
                if group and time_ns != group_time:
                    yield group_time, group
                    group = []
                group_time = time_ns
                group.append((topic, raw))
        except BagDamaged as exc:
            self.damage = str(exc)
            self.get_logger().error(f'{exc}; stopping after the last whole frame before the damage')
            return
        if group:
            yield group_time, group

    def play(self) -> int:
        s = self.settings
        image_pubs = {t: p for t, p in self.pubs.items() if 'image' in t}
        if s.wait_for_subscribers:
            self.get_logger().info(f'waiting for {s.wait_for_subscribers} subscriber(s) on each image topic')
            subscribers = SubscribersReady(image_pubs, s.wait_for_subscribers)
            while rclpy.ok() and not subscribers.ready(time.monotonic()):
                if short := subscribers.short():
                    self.get_logger().info(
                        'still waiting: '
                        + ', '.join(f'{t} {n}/{s.wait_for_subscribers}' for t, n in sorted(short.items())),
                        throttle_duration_sec=10.0,
                    )
                self._spin_for(0.1)
        if self.lockstep_sub is not None and self.lockstep_sub.get_publisher_count() < 1:
            self.get_logger().info(f'waiting for a publisher on {s.lockstep_topic}')
            self._spin_for(3600, lambda: self.lockstep_sub.get_publisher_count() >= 1)
        start_at = self._start_time(s.start_topic) if s.start_topic else s.start_at
        count, previous_ns, wall_start, bag_start = 0, None, time.monotonic(), None
        if start_at:  # players of several hosts release frame k together (cameras on a common clock)
            wall_start += start_at - time.time()
        for time_ns, group in self.frames():
            if not rclpy.ok():
                break
            if bag_start is None:
                bag_start = time_ns
            if not s.lockstep:  # recorded timing, scaled
                due = wall_start + (time_ns - bag_start) * 1e-9 / s.rate
                if start_at and time.monotonic() - due > 0.5 * self.sequence_clock.frame_period / s.rate:
                    self.skipped += 1  # ready too late for it: a live camera publishes the present
                    continue
                self._spin_for(max(0.0, due - time.monotonic()))
            self.clock_pub.publish(Clock(clock=seconds_to_stamp(time_ns * 1e-9)))
            for topic, raw in group:
                self.pubs[topic].publish(raw)
            count += 1
            if s.lockstep:
                self.lockstep.sent(
                    time_ns * 1e-9,
                    f'frame {self.sequence_clock.frame_ns(time_ns)} (t={time_ns * 1e-9:.3f} s) on {s.lockstep_topic}',
                )
            previous_ns = time_ns
        self.lockstep.finish()
        timed_out = self.lockstep.timed_out
        # Reliable subscribers must get the last frame before the process exits.
        for pub in [*self.pubs.values(), self.clock_pub]:
            pub.wait_for_all_acked(Duration(seconds=5.0))
        self.get_logger().info(
            f'played {count} frames'
            + (
                f' up to frame {self.sequence_clock.frame_ns(previous_ns)} (t={previous_ns * 1e-9:.3f} s)'
                if previous_ns
                else ''
            )
            + (f'; lockstep timed out for {len(timed_out)} of them' if timed_out else '')
            + (f'; skipped {self.skipped} frames due before it was ready' if self.skipped else '')
        )
        return count


def main(argv=None) -> int:
    cli, argv = parse_node_args(BagPlayerSettings, argv, __doc__)
    rclpy.init(args=argv)
    node = BagPlayer(cli)
    try:
        played = node.play()
        if not node.settings.exit_when_done:
            spin_until(node.spinner)
    except KeyboardInterrupt:
        played = 0
    finally:
        node.spinner.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
    return 1 if not played else (4 if node.damage else 3 if node.lockstep.timed_out else 0)


if __name__ == '__main__':
    raise SystemExit(main())
