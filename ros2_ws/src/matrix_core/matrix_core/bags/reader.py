"""Reading rosbag2 folders (MCAP or SQLite) with ``rosbags``: raw messages and decoded sequence frames."""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rosbags.rosbag2 import Reader

from matrix_core import message_fields as fields
from matrix_core.bags.messages import TYPESTORE
from matrix_core.bags.salvage import raw_messages
from matrix_core import topics as t


@dataclass
class BagMessage:
    """One message: topic, ROS type name, bag time (ns) and the deserialised ``rosbags`` message object."""

    topic: str
    msgtype: str
    time_ns: int
    msg: object


def bag_topics(path) -> dict:
    """topic -> (message type, message count) of a bag folder."""
    with Reader(Path(path)) as reader:
        return {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}


def read_bag(path, topics=None):
    """Yield :class:`BagMessage` in bag-time order, optionally only for ``topics`` (iterable of names). A
    damaged or unfinished bag yields the messages before the damage, then raises
    :class:`~matrix_core.bags.salvage.BagDamaged` (see there)."""
    for topic, msgtype, time_ns, raw in raw_messages(path, None if topics is None else set(topics)):
        yield BagMessage(topic, msgtype, time_ns, TYPESTORE.deserialize_cdr(raw, msgtype))


@dataclass
class SequenceFrame:
    """All messages of one header stamp, decoded: images/cameras per view, positions per person id."""

    stamp_ns: int
    images: dict = field(default_factory=dict)
    cameras: dict = field(default_factory=dict)
    positions: dict = field(default_factory=dict)


def read_sequence_frames(path):
    """Yield :class:`SequenceFrame` per header stamp of a sequence bag (see the package docstring).

    A frame is complete when the stamp changes, so the bag must be in time order (as written by
    :class:`~matrix_core.bags.writer.SequenceBagWriter`). Raises ValueError on a malformed message. A damaged
    bag yields its whole frames before the damage, then raises :class:`~matrix_core.bags.salvage.BagDamaged`
    (the frame the damage cut is not yielded in part).
    """
    current, poses, ids = None, None, None

    def finish(frame):
        if poses is not None:
            keys = ids if ids is not None and len(ids) == len(poses) else range(len(poses))
            frame.positions = dict(zip(keys, poses))
        return frame

    for bm in read_bag(path):
        stamp = fields.stamp_ns(bm.msg.header) if hasattr(bm.msg, 'header') else bm.time_ns
        if current is not None and stamp != current.stamp_ns:
            yield finish(current)
            current, poses, ids = None, None, None
        if current is None:
            current = SequenceFrame(stamp)
        view = bm.topic.split('/')[1]
        if bm.msgtype in (t.IMAGE_TYPE, t.COMPRESSED_TYPE):
            current.images[view] = fields.image_from_msg(bm.msg)
        elif bm.msgtype == t.CAMERA_INFO_TYPE:
            current.cameras[view] = fields.camera_from_camera_info(bm.msg)
        elif bm.topic == t.PEDESTRIANS_TOPIC:
            poses = [np.array([p.position.x, p.position.y, p.position.z]) for p in bm.msg.poses]
        elif bm.topic == t.PEDESTRIAN_IDS_TOPIC:
            ids = [int(i) for i in bm.msg.data]
    if current is not None:
        yield finish(current)
