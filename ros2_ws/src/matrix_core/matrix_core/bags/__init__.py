"""rosbag2 (MCAP) writing and reading with the pure-Python ``rosbags`` library (no rclpy).

Topics of a sequence bag (frame ids: ``world`` and ``D{n}/camera_optical``; header stamps
``start_time + frame_index * frame_period``, 0.5 s apart by default; the bag's receive time equals the stamp):

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

from matrix_core.bags.reader import BagMessage, bag_topics, read_bag, read_sequence_frames
from matrix_core.bags.writer import SequenceBagWriter, write_sequence_bag

__all__ = ['BagMessage', 'SequenceBagWriter', 'bag_topics', 'read_bag', 'read_sequence_frames',
           'write_sequence_bag']
