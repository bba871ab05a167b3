"""rosbag2 (MCAP) writing and reading with the pure-Python ``rosbags`` library (no rclpy).

Topics of a sequence bag (frame ids: ``world`` and ``D{n}/camera_optical``; header stamps from the sequence
clock, ``start_time + frame_index * frame_period`` (1.0 s + 0.5 s per frame by default), which the bag stores in
its metadata, see :mod:`matrix_core.bags.clock`; the bag's receive time equals the stamp):

- ``/D{n}/image_raw`` (``sensor_msgs/msg/Image``, bgr8) or ``/D{n}/image/compressed``
  (``sensor_msgs/msg/CompressedImage``, jpeg) per drone;
- ``/D{n}/ground_truth/camera_info`` (``sensor_msgs/msg/CameraInfo``): ``k``, ``d``, ``r = I`` and
  ``p = K [R | t]`` mapping WORLD metres to pixels (same convention as ``matrix_ros.conversions``);
- ``/D{n}/ground_truth/pose`` (``geometry_msgs/msg/PoseStamped``): ``world_T_cam`` of the optical frame;
- ``/ground_truth/pedestrians`` (``geometry_msgs/msg/PoseArray``, frame ``world``): one pose per person,
  position = foot point (z = 0), identity orientation, ordered by person id; the ids themselves are in
  ``/ground_truth/pedestrian_ids`` (``std_msgs/msg/Int32MultiArray``, same order).

Everything is in the internal convention of :mod:`matrix_core.geometry.camera`.
"""

import importlib

# Names are imported on first use: the clock (read by settings dataclasses, so by every CLI start) must not
# pull in rosbags and the message code.
_MODULE_OF = {
    'SequenceClock': 'clock',
    'DEFAULT_CLOCK': 'clock',
    'read_sequence_clock': 'clock',
    'BagMessage': 'reader',
    'bag_topics': 'reader',
    'read_bag': 'reader',
    'read_sequence_frames': 'reader',
    'SequenceBagWriter': 'writer',
    'write_sequence_bag': 'writer',
    'BagDamaged': 'salvage',
    'raw_messages': 'salvage',
}

__all__ = sorted(_MODULE_OF)


def __getattr__(name):
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)
