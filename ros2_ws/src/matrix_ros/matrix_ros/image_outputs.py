"""The fuse node's per-drone image outputs: ``<view>/detections_2d`` (matrix_msgs/Detection2DArray), its twin
``<view>/vision/detections_2d`` (vision_msgs/Detection2DArray, ``matrix_ros.vision_messages``) and, with
``overlay``, ``<view>/overlay/compressed`` (the image with the boxes and ids drawn). Boxes and cameras come
from the core (``matrix_core.fusion.image_outputs``); stamp = the frame's, frame_id = the drone's optical
frame (``topics.optical_frame``)."""

from matrix_msgs.msg import Detection2DArray
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header
from vision_msgs.msg import Detection2DArray as VisionDetection2DArray

from matrix_core import topics
from matrix_core.datasets.drone_inputs import open_references
from matrix_core.fusion.image_outputs import ViewCameras
from matrix_core.message_fields import ConversionError, image_from_msg
from matrix_core.site.parameter import named_site
from matrix_ros import diagnostics
from matrix_ros import fusion_messages as out
from matrix_ros import vision_messages as vm
from matrix_ros.left_out import start_up_statuses
from matrix_ros.qos import publisher_qos


class ImageOutputs:
    """Publishers of every view's image outputs (none when ``detections_2d_topic`` is empty); ``statuses``: a
    ``fuse/<view>/start_up`` DiagnosticStatus (WARN, the reason) per view whose reference cannot be read."""

    def __init__(self, node, settings):
        s, self.node = settings, node
        if s.scene_dataset:
            self.cameras = ViewCameras.from_dataset(s, s.scene_dataset, s.views)
        elif s.site_references:  # the site file's references: the intrinsics of each drone's reference
            self.cameras = ViewCameras.from_references(s, open_references(site=named_site(s.site)), s.views)
        else:
            self.cameras = ViewCameras(s)
        qos = publisher_qos()
        self.boxes = (
            {v: node.create_publisher(Detection2DArray, s.topic(s.detections_2d_topic, v), qos) for v in s.views}
            if s.detections_2d_topic
            else {}
        )
        self.vision = {
            v: node.create_publisher(VisionDetection2DArray, topics.drone_topic(v, topics.VISION_DETECTIONS_2D), qos)
            for v in self.boxes
        }
        self.overlays = (
            {v: node.create_publisher(CompressedImage, s.topic(s.overlay_topic, v), qos) for v in self.boxes}
            if s.overlay
            else {}
        )
        if self.boxes and s.input_kind == 'homography' and not self.cameras.intrinsics and not self.cameras.unavailable:
            node.get_logger().warning(
                'no detections_2d from homographies: neither scene_dataset nor site_references gives the intrinsics'
            )
        # A view whose reference cannot be read is still fused; only its boxes from homographies need the
        # reference's intrinsics. Said once here, and in every frame's diagnostics (``statuses``).
        consequence = 'no image boxes' if self.boxes and s.input_kind == 'homography' else 'reference unusable'
        for view, why in sorted(self.cameras.unavailable.items()):
            node.get_logger().warning(f'{view}: {consequence}: {why} (its images are fused all the same)')
        self.statuses = start_up_statuses(node.get_name(), self.cameras.unavailable, diagnostics.WARN, consequence)

    def publish(self, stamp, frame, tracks) -> None:
        """Boxes of ``tracks`` in every view that has a camera this frame (a synchronised ``frame``)."""
        if not self.boxes:
            return
        geometry = {v: frame.items.get(f'{v}/geometry') for v in self.boxes}
        for view, boxes in self.cameras.frame_boxes(geometry, tracks).items():
            header = Header(stamp=stamp, frame_id=topics.optical_frame(view))
            self.boxes[view].publish(out.detections_2d_msg(header, boxes))
            self.vision[view].publish(vm.detections_2d_msg(header, boxes))
            image = frame.items.get(f'{view}/image')
            if view in self.overlays and image is not None:
                try:
                    self.overlays[view].publish(out.overlay_msg(header, image_from_msg(image), boxes))
                except ConversionError as exc:
                    self.node.get_logger().error(f'{view}: no overlay: {exc}')
