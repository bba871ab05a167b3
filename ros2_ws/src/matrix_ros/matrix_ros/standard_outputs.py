"""The fuse node's graph-wide outputs again in standard types (``matrix_ros.vision_messages``):
``vision/tracks`` and ``vision/detections`` (vision_msgs/Detection3DArray, the header of the matrix_msgs
twins) and the fixed frames on ``/tf_static`` (world -> area, once: transient local, as tf2's static
broadcaster; stamp 0: a static transform holds at every time). Per-drone image boxes:
``matrix_ros.image_outputs``; camera poses on ``/tf``: calib."""

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from vision_msgs.msg import Detection3DArray
from tf2_msgs.msg import TFMessage

from matrix_core import topics
from matrix_ros import vision_messages as vm
from matrix_ros.qos import publisher_qos

# What tf2's StaticTransformBroadcaster offers: every static transform of a publisher in its one latched message.
STATIC_TF_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)


class StandardOutputs:
    """Publishers of the Detection3DArray twins; publishes /tf_static once. ``settings``: the fuse node's
    (``person_radius_m``, ``person_height_m``: the box of a person); ``area``: (x_min, y_min, x_max, y_max) m."""

    def __init__(self, node, settings, area):
        qos = publisher_qos()
        self.size = (2 * settings.person_radius_m, settings.person_height_m)
        self.tracks = node.create_publisher(Detection3DArray, topics.VISION_TRACKS, qos)
        self.detections = node.create_publisher(Detection3DArray, topics.VISION_DETECTIONS, qos)
        self.static = node.create_publisher(TFMessage, topics.TF_STATIC_TOPIC, STATIC_TF_QOS)
        self.static.publish(vm.tf_msg(vm.area_transform(settings.world_frame, area)))

    def publish(self, header, result, frame_interval_s: float) -> None:
        """The twins of one fused frame (``result``: a FusionResult) with the matrix_msgs outputs' ``header``."""
        self.tracks.publish(vm.tracks_3d_msg(header, result.tracks, self.size))
        self.detections.publish(vm.detections_3d_msg(header, result.detections, frame_interval_s, self.size))
