"""Writing sequence bags (rosbag2, MCAP storage) with ``rosbags``; topics in the package docstring, the
sequence clock (stored in the bag's metadata) in :mod:`matrix_core.bags.clock`."""

from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer

from matrix_core.bags import messages as m
from matrix_core import topics as t
from matrix_core.bags.clock import SequenceClock


class SequenceBagWriter:
    """Streams frames of a multi-view sequence into a new rosbag2 folder ``path`` (must not exist).

    Args:
        path: bag folder to create.
        views: view names ('D1', ...).
        compressed: write ``/D{n}/image/compressed`` (JPEG) instead of ``/D{n}/image_raw``.
        clock: :class:`SequenceClock` (default: first stamp 1.0 s, 0.5 s per frame); frame index i gets
            the header stamp ``clock.stamp(i)``. It is stored in the bag's metadata (custom data).

    Use as a context manager; call :meth:`write_frame` once per frame, in order.
    """

    def __init__(self, path, views, compressed: bool = False, clock: SequenceClock = None):
        self.path = Path(path)
        if self.path.exists():
            raise FileExistsError(f'bag folder {self.path} already exists')
        self.views = list(views)
        self.compressed = compressed
        self.clock = clock or SequenceClock()
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        for key, value in self.clock.custom_data().items():
            self._writer.set_custom_data(key, value)
        self._conn = {}

    def __enter__(self):
        self._writer.open()
        for v in self.views:
            image_type = t.COMPRESSED_TYPE if self.compressed else t.IMAGE_TYPE
            self._add(t.image_topic(v, self.compressed), image_type)
            self._add(t.camera_info_topic(v), t.CAMERA_INFO_TYPE)
            self._add(t.pose_topic(v), t.POSE_TYPE)
        self._add(t.PEDESTRIANS_TOPIC, t.POSE_ARRAY_TYPE)
        self._add(t.PEDESTRIAN_IDS_TOPIC, t.IDS_TYPE)
        return self

    def _add(self, topic, msgtype):
        self._conn[topic] = (self._writer.add_connection(topic, msgtype, typestore=m.TYPESTORE), msgtype)

    def _write(self, topic, stamp, msg):
        conn, msgtype = self._conn[topic]
        self._writer.write(conn, stamp, m.TYPESTORE.serialize_cdr(msg, msgtype))

    def write_frame(self, index: int, images: dict, cameras: dict, positions: dict) -> int:
        """Write frame ``index``: images (view -> (H, W, 3) BGR), cameras (view -> Camera), positions (person
        id -> (3,) metres). Returns the stamp in nanoseconds."""
        stamp = self.clock.stamp_ns(index)
        for v in self.views:
            hdr = m.header(stamp, t.optical_frame(v))
            img = images[v]
            msg = m.compressed_msg(img, hdr) if self.compressed else m.image_msg(img, hdr)
            self._write(t.image_topic(v, self.compressed), stamp, msg)
            self._write(t.camera_info_topic(v), stamp, m.camera_info_msg(cameras[v], hdr))
            self._write(t.pose_topic(v), stamp, m.pose_msg(cameras[v], m.header(stamp, t.WORLD_FRAME)))
        poses, ids = m.pedestrians_msg(positions, m.header(stamp, t.WORLD_FRAME))
        self._write(t.PEDESTRIANS_TOPIC, stamp, poses)
        self._write(t.PEDESTRIAN_IDS_TOPIC, stamp, ids)
        return stamp

    def __exit__(self, *exc):
        self._writer.close()


def write_sequence_bag(
    dataset, path, compressed: bool = False, clock: SequenceClock = None, progress: bool = True
) -> Path:
    """Write any MATRIX-format dataset (simulated or the real sample) as a sequence bag at ``path``.

    Args:
        dataset: a :class:`~matrix_core.datasets.MatrixDataset` (or any reader with the same interface).
    """
    from tqdm import tqdm

    with SequenceBagWriter(path, dataset.views, compressed, clock) as bag:
        for i, frame in enumerate(tqdm(dataset.frames, desc='bag', unit='frame', disable=not progress)):
            images = {v: dataset.load_image(v, frame) for v in dataset.views}
            cameras = {v: dataset.camera(v, frame) for v in dataset.views}
            bag.write_frame(i, images, cameras, dataset.pedestrian_positions(frame))
    return Path(path)
