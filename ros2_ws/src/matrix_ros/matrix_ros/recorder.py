"""``recorder``: write what the graph publishes to a rosbag2 (MCAP), and tracks to MOT-style text.

Every topic in ``topics`` (with its type at the same index of ``types``) is stored as received
(serialized CDR, no re-encoding), with the node's clock as bag time (the bag's time under
``use_sim_time``). Subscriptions use QoS ``qos``: ``history`` (default) also gets the last messages
published before the recorder matched (this workspace's publishers offer them), so a recorder that joins
a moment late loses nothing; a volatile publisher needs ``qos:=reliable``. With ``tracks_topic`` set, each
``matrix_msgs/TrackArray`` also becomes lines
``frame id x y`` in ``mot_file`` (frame = round((stamp - start_time) / frame_period); metres, world
frame), the format ``matrix-tracker score`` reads. The sequence clock (``start_time``, ``frame_period``) is the
one stored in ``sequence_bag`` (the bag being replayed; see ``matrix_core.bags.clock``), else the default
(1.0 s, 0.5 s); the parameters override it. The recorder's bag stores the clock it used, as a sequence bag
does. The bag is closed cleanly on Ctrl-C / SIGTERM; what was received is also put on disk every
``flush_period_s``, so a recorder that is killed keeps a bag whose messages up to the last flush are read back
by ``matrix_core.bags.read_bag`` (which then raises ``BagDamaged``: no ``metadata.yaml``, no index) and its MOT
text, written line by line.
"""

import math
from dataclasses import dataclass, field
from pathlib import Path

from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
from rclpy.clock import Clock, ClockType
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from matrix_core import topics
from matrix_core.bags.clock import SequenceClock, read_sequence_clock
from matrix_core.message_fields import stamp_seconds
from matrix_core.metrics.bev_points import BevPoints, bev_point_lines
from matrix_ros.message_types import message_class
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import qos_by_name


@dataclass
class RecorderSettings:
    out: str = field(default='', metadata={'help': 'bag folder to create (must not exist)'})
    topics: list[str] = field(default_factory=list, metadata={'help': 'topics to record'})
    types: list[str] = field(
        default_factory=list, metadata={'help': 'message type of each topic, e.g. sensor_msgs/msg/CameraInfo'}
    )
    tracks_topic: str = field(
        default='', metadata={'help': 'matrix_msgs/TrackArray topic to export as text (empty: none)'}
    )
    mot_file: str = field(default='', metadata={'help': 'text file for the tracks (default: OUT.tracks.txt)'})
    sequence_bag: str = field(
        default='',
        metadata={
            'help': 'the sequence bag being replayed: its stored clock numbers the MOT frames (empty: 1.0 s, 0.5 s)'
        },
    )
    start_time: float = field(default=math.nan, metadata={'help': 'stamp of frame 0, seconds (NaN: the clock\'s)'})
    frame_period: float = field(default=math.nan, metadata={'help': 'seconds between frames (NaN: the clock\'s)'})
    flush_period_s: float = field(
        default=1.0,
        metadata={
            'help': 'write what was received to disk every this many (wall) seconds, so a recorder that is killed '
            'loses at most that much (0: only when closed)'
        },
    )
    qos: str = field(
        default='history',
        metadata={
            'help': 'QoS of the subscriptions: history (transient local: also what was published before matching), '
            'reliable (volatile publishers) or sensor_data'
        },
    )

    def __post_init__(self):
        if len(self.topics) != len(self.types):
            raise ValueError(f'topics ({len(self.topics)}) and types ({len(self.types)}) must pair up')
        if self.frame_period <= 0:
            raise ValueError('frame_period must be positive')
        if not self.flush_period_s >= 0:
            raise ValueError(f'flush_period_s must be >= 0, got {self.flush_period_s}')
        qos_by_name(self.qos)

    def clock(self) -> SequenceClock:
        """The sequence clock: ``sequence_bag``'s (or the default), with the parameters that are set."""
        clock = read_sequence_clock(self.sequence_bag) if self.sequence_bag else SequenceClock()
        return clock.overridden(self.start_time, self.frame_period)


def _typestore():
    """Jazzy's standard types plus this workspace's matrix_msgs (read from its installed .msg files)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    try:
        msg_dir = Path(get_package_share_directory('matrix_msgs')) / 'msg'
    except PackageNotFoundError:
        return store
    types = {}
    for path in sorted(msg_dir.glob('*.msg')):
        types.update(get_types_from_msg(path.read_text(), f'matrix_msgs/msg/{path.stem}'))
    store.register(types)
    return store


class Recorder(SettingsNode):
    def __init__(self, defaults: RecorderSettings):
        super().__init__('recorder')
        self.settings = s = declare_settings(self, RecorderSettings, defaults)
        if not s.out:
            raise ValueError('parameter out must name the bag folder to create')
        if Path(s.out).exists():
            raise FileExistsError(f'{s.out} exists; rosbag2 writes a new folder')
        self.clock = s.clock()
        store = _typestore()
        self.writer = Writer(Path(s.out), version=9, storage_plugin=StoragePlugin.MCAP)
        for key, value in self.clock.custom_data().items():
            self.writer.set_custom_data(key, value)
        self.writer.open()
        self.counts, self.unflushed = {}, 0
        for topic, type_name in zip(s.topics, s.types):
            conn = self.writer.add_connection(topic, type_name, typestore=store)
            self.counts[topic] = 0
            self.create_subscription(
                message_class(type_name),
                topic,
                lambda raw, c=conn, t=topic: self._write(c, t, raw),
                qos_by_name(s.qos, 100),
                raw=True,
            )
        self.mot = None
        if s.tracks_topic:
            self.mot = open(s.mot_file or f'{s.out}.tracks.txt', 'w')
            self.create_subscription(
                message_class(topics.TRACK_ARRAY_TYPE), s.tracks_topic, self._tracks, qos_by_name(s.qos, 100)
            )
        if s.flush_period_s > 0:  # wall time: under use_sim_time the bag's clock may stop or go back
            self.create_timer(s.flush_period_s, self.flush, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(f'recording {len(s.topics)} topics to {s.out}; frames: {self.clock.describe()}')

    def flush(self) -> None:
        """Put the messages received since the last flush on disk as a finished MCAP chunk. rosbags keeps up
        to 1 MiB in memory and writes the file's index only on close: a recorder killed (SIGKILL, power) would
        lose all of a slow stream. Its chunks on disk are read back by ``matrix_core.bags.salvage``.

        rosbags' public ``Writer`` has no ``flush()`` (0.11, pinned in constraints.txt): this calls the two
        members of its MCAP storage that one would be, ``close_chunk()`` (what ``write`` calls at 1 MiB; a
        chunk without messages is harmless) and the flush of its file, and reads nothing of its state."""
        if self.unflushed:
            self.writer.storage.close_chunk()
            self.writer.storage.bio.flush()
            self.unflushed = 0

    def _write(self, conn, topic, raw: bytes):
        self.writer.write(conn, self.get_clock().now().nanoseconds, raw)
        self.counts[topic] += 1
        self.unflushed += 1

    def _tracks(self, msg):
        stamp = stamp_seconds(msg.header.stamp)
        frame = self.clock.frame(stamp)
        finite = [math.isfinite(t.position.x) and math.isfinite(t.position.y) for t in msg.tracks]
        tracks = [t for t, ok in zip(msg.tracks, finite) if ok]
        if not all(finite):  # a track without a position cannot be scored: said, the others written
            bad = [t.id for t, ok in zip(msg.tracks, finite) if not ok]
            self.get_logger().error(f'{self.settings.tracks_topic} t={stamp:.3f} s: track(s) {bad} not finite')
        xy = [(t.position.x, t.position.y) for t in tracks]
        self.mot.write(bev_point_lines(BevPoints([frame] * len(xy), xy, ids=[t.id for t in tracks])))
        self.mot.flush()

    def close(self):
        self.writer.close()
        if self.mot is not None:
            self.mot.close()
        self.get_logger().info(f'closed {self.settings.out}: ' + ', '.join(f'{t} {n}' for t, n in self.counts.items()))


def main(argv=None) -> int:
    return spin_node(Recorder, RecorderSettings, argv, description=__doc__, on_exit=Recorder.close)


if __name__ == '__main__':
    raise SystemExit(main())
