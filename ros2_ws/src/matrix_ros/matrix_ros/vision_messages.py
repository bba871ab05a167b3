"""The outputs in the standard ROS 2 perception types, for stacks that know none of ours
(docs/standard-interfaces.md): tracks and detections as ``vision_msgs/Detection3DArray``, a drone's image
boxes as ``vision_msgs/Detection2DArray``, camera poses and the fixed frames as ``tf2_msgs/TFMessage``.

A person is a box standing on the ground: centre ``(x, y, height / 2)`` in the world frame, size
``(diameter, diameter, height)``; ``Detection3D`` has no velocity, so the box's yaw follows the direction of
motion (identity below ``MOVING_SPEED_M_S``, where the direction is noise); the speed itself stays in
``matrix_msgs/TrackArray``.
"""

import math

from geometry_msgs.msg import TransformStamped
from tf2_msgs.msg import TFMessage
from vision_msgs.msg import (
    BoundingBox2D,
    BoundingBox3D,
    Detection2D,
    Detection2DArray,
    Detection3D,
    Detection3DArray,
    ObjectHypothesisWithPose,
)

from matrix_core import topics

MOVING_SPEED_M_S = 0.2  # below: a standing person, whose velocity estimate points anywhere


def _hypothesis(score: float, pose=None) -> ObjectHypothesisWithPose:
    h = ObjectHypothesisWithPose()
    h.hypothesis.class_id, h.hypothesis.score = topics.PERSON_CLASS_ID, float(score)
    if pose is not None:
        h.pose.pose = pose
    return h


def person_detection(header, xy, score: float, velocity=None, track_id: str = '', size=(0.5, 1.8)) -> Detection3D:
    """One person: ``xy`` (2,) world metres, ``velocity`` (2,) m/s or None, ``size`` (diameter, height) m."""
    diameter, height = (float(v) for v in size)
    box = BoundingBox3D()
    box.center.position.x, box.center.position.y, box.center.position.z = float(xy[0]), float(xy[1]), height / 2
    box.center.orientation.w = 1.0
    if velocity is not None and math.hypot(velocity[0], velocity[1]) >= MOVING_SPEED_M_S:
        yaw = math.atan2(float(velocity[1]), float(velocity[0]))
        box.center.orientation.z, box.center.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    box.size.x = box.size.y = diameter
    box.size.z = height
    return Detection3D(header=header, results=[_hypothesis(score, box.center)], bbox=box, id=track_id)


def tracks_3d_msg(header, tracks, size=(0.5, 1.8)) -> Detection3DArray:
    """matrix_core.tracking tracks -> Detection3DArray (id = the track id as text)."""
    return Detection3DArray(
        header=header,
        detections=[person_detection(header, t.xy, t.score, t.velocity, str(t.track_id), size) for t in tracks],
    )


def detections_3d_msg(header, dets, frame_interval_s: float, size=(0.5, 1.8)) -> Detection3DArray:
    """BevDetections -> Detection3DArray (no id); motion from the network's tracking offset, which points to the
    previous frame's position ``frame_interval_s`` earlier (as ``fusion_messages.detections_msg``)."""
    out = Detection3DArray(header=header)
    for k in range(len(dets)):
        velocity = None if dets.offsets is None else -dets.offsets[k] / frame_interval_s
        out.detections.append(person_detection(header, dets.xy[k], float(dets.scores[k]), velocity, '', size))
    return out


def detections_2d_msg(header, boxes) -> Detection2DArray:
    """matrix_core.fusion.image_boxes ImageBoxes of one drone -> vision_msgs Detection2DArray (pixels, header: the
    frame's stamp and the drone's optical frame; id = the fused track id as text)."""
    out = Detection2DArray(header=header)
    for b in boxes:
        x0, y0, x1, y1 = (float(v) for v in b.box)
        bbox = BoundingBox2D(size_x=x1 - x0, size_y=y1 - y0)
        bbox.center.position.x, bbox.center.position.y = (x0 + x1) / 2, (y0 + y1) / 2
        out.detections.append(
            Detection2D(header=header, results=[_hypothesis(b.score)], bbox=bbox, id=str(int(b.track_id)))
        )
    return out


def pose_transform(pose_stamped, child_frame: str) -> TransformStamped:
    """A PoseStamped of ``child_frame`` in its header's frame (``world_T_cam``: maps the child to the parent)
    -> the same transform for /tf (tf2's ``parent_T_child``: the same numbers)."""
    t = TransformStamped(header=pose_stamped.header, child_frame_id=child_frame)
    p, q = pose_stamped.pose.position, pose_stamped.pose.orientation
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = p.x, p.y, p.z
    t.transform.rotation = q
    return t


def area_transform(world_frame: str, area) -> TransformStamped:
    """world -> area: ``area`` (x_min, y_min, x_max, y_max) metres; the area frame sits at its corner
    (x_min, y_min, 0) with the world's axes."""
    t = TransformStamped(child_frame_id=topics.AREA_FRAME)
    t.header.frame_id = world_frame
    t.transform.translation.x, t.transform.translation.y = float(area[0]), float(area[1])
    t.transform.rotation.w = 1.0
    return t


def tf_msg(*transforms) -> TFMessage:
    return TFMessage(transforms=list(transforms))
