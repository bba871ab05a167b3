"""ROS messages and the scene's geometry (``matrix_core.live_scene``) as Foxglove SDK messages: what the live
view sends. Entities carry a frame id; the viewer places them by the transforms it was sent (``/tf``)."""

import numpy as np
from foxglove.messages import (
    CameraCalibration,
    Color,
    CompressedImage,
    CubePrimitive,
    CylinderPrimitive,
    FrameTransform,
    FrameTransforms,
    Grid,
    LinePrimitive,
    LinePrimitiveLineType,
    PackedElementField,
    PackedElementFieldNumericType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SceneEntityDeletion,
    SceneEntityDeletionType,
    SceneUpdate,
    TextPrimitive,
    Timestamp,
    Vector2,
    Vector3,
)

from matrix_core.live_scene import area_outline, frustum_segments, track_rgb

IDENTITY = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
AREA_COLOUR = Color(r=0.3, g=0.8, b=1.0, a=1.0)
BLOCK_COLOUR = Color(r=0.55, g=0.1, b=0.1, a=0.6)  # the MATRIX block is dark red
FRUSTUM_COLOUR = Color(r=1.0, g=0.85, b=0.2, a=1.0)
WHITE = Color(r=1.0, g=1.0, b=1.0, a=1.0)


def timestamp(stamp) -> Timestamp:
    """builtin_interfaces/Time -> Timestamp."""
    return Timestamp(sec=int(stamp.sec), nsec=int(stamp.nanosec))


def _points(xyz) -> list:
    return [Point3(x=float(p[0]), y=float(p[1]), z=float(p[2])) for p in xyz]


def _pose(x=0.0, y=0.0, z=0.0) -> Pose:
    return Pose(position=Vector3(x=float(x), y=float(y), z=float(z)), orientation=IDENTITY)


def frame_transforms(tf_message) -> FrameTransforms:
    """tf2_msgs/TFMessage -> FrameTransforms (the same parent_T_child numbers)."""
    out = []
    for t in tf_message.transforms:
        p, q = t.transform.translation, t.transform.rotation
        out.append(
            FrameTransform(
                timestamp=timestamp(t.header.stamp),
                parent_frame_id=t.header.frame_id,
                child_frame_id=t.child_frame_id,
                translation=Vector3(x=p.x, y=p.y, z=p.z),
                rotation=Quaternion(x=q.x, y=q.y, z=q.z, w=q.w),
            )
        )
    return FrameTransforms(transforms=out)


def grid(occupancy) -> Grid:
    """nav_msgs/OccupancyGrid (the BEV heatmap, 0-100, -1 unknown) -> Grid of one int8 field ``heat``."""
    info = occupancy.info
    o = info.origin
    return Grid(
        timestamp=timestamp(occupancy.header.stamp),
        frame_id=occupancy.header.frame_id,
        pose=Pose(
            position=Vector3(x=o.position.x, y=o.position.y, z=o.position.z),
            orientation=Quaternion(x=o.orientation.x, y=o.orientation.y, z=o.orientation.z, w=o.orientation.w),
        ),
        column_count=int(info.width),
        cell_size=Vector2(x=info.resolution, y=info.resolution),
        row_stride=int(info.width),
        cell_stride=1,
        fields=[PackedElementField(name='heat', offset=0, type=PackedElementFieldNumericType.Int8)],
        data=bytes(occupancy.data),
    )


def compressed_image(msg) -> CompressedImage:
    """sensor_msgs/CompressedImage -> CompressedImage (the same JPEG bytes)."""
    return CompressedImage(
        timestamp=timestamp(msg.header.stamp), frame_id=msg.header.frame_id, data=bytes(msg.data), format=msg.format
    )


def calibration(info) -> CameraCalibration:
    """sensor_msgs/CameraInfo -> CameraCalibration (the image panel's and the 3D panel's camera model)."""
    return CameraCalibration(
        timestamp=timestamp(info.header.stamp),
        frame_id=info.header.frame_id,
        width=int(info.width),
        height=int(info.height),
        distortion_model=info.distortion_model or 'plumb_bob',
        D=[float(v) for v in info.d],
        K=[float(v) for v in info.k],
        R=[float(v) for v in info.r],
        P=[float(v) for v in info.p],
    )


def frustum_entity(stamp, view: str, info, depth_m: float) -> SceneEntity:
    """The camera of CameraInfo ``info`` as a frustum in its optical frame (frame-locked: it moves with /tf)."""
    segments = frustum_segments(np.reshape(info.k, (3, 3)), int(info.width), int(info.height), depth_m)
    return SceneEntity(
        timestamp=timestamp(stamp),
        frame_id=info.header.frame_id,
        id=f'camera/{view}',
        frame_locked=True,
        lines=[
            LinePrimitive(
                type=LinePrimitiveLineType.LineList,
                pose=_pose(),
                thickness=2.0,
                scale_invariant=True,
                points=_points(segments),
                color=FRUSTUM_COLOUR,
            )
        ],
        texts=[
            TextPrimitive(pose=_pose(), billboard=True, font_size=14.0, scale_invariant=True, color=WHITE, text=view)
        ],
    )


def area_entities(stamp, world_frame: str, area, boxes) -> list:
    """The area's outline and each obstacle box ((K, 5) x0 y0 x1 y1 height) in the world frame."""
    ts = timestamp(stamp)
    cubes = [
        CubePrimitive(
            pose=_pose((b[0] + b[2]) / 2, (b[1] + b[3]) / 2, b[4] / 2),
            size=Vector3(x=float(b[2] - b[0]), y=float(b[3] - b[1]), z=float(b[4])),
            color=BLOCK_COLOUR,
        )
        for b in boxes
    ]
    outline = LinePrimitive(
        type=LinePrimitiveLineType.LineStrip,
        pose=_pose(),
        thickness=3.0,
        scale_invariant=True,
        points=_points(area_outline(area)),
        color=AREA_COLOUR,
    )
    return [
        SceneEntity(timestamp=ts, frame_id=world_frame, id='area', lines=[outline]),
        SceneEntity(timestamp=ts, frame_id=world_frame, id='obstacles', cubes=cubes),
    ]


def tracks_update(track_array, trails: dict, size=(0.5, 1.8)) -> SceneUpdate:
    """matrix_msgs/TrackArray -> SceneUpdate: the previous frame's tracks deleted, per track a cylinder
    (``size``: diameter, height m), its id above it and its trail (``trails``: id -> (M, 2) positions)."""
    ts, frame = timestamp(track_array.header.stamp), track_array.header.frame_id
    diameter, height = size
    entities = []
    for t in track_array.tracks:
        r, g, b = track_rgb(t.id)
        colour = Color(r=r, g=g, b=b, a=0.85)
        x, y = t.position.x, t.position.y
        trail = trails.get(t.id)
        lines = (
            [
                LinePrimitive(
                    type=LinePrimitiveLineType.LineStrip,
                    pose=_pose(),
                    thickness=2.0,
                    scale_invariant=True,
                    points=_points(np.column_stack([trail, np.full(len(trail), 0.05)])),
                    color=colour,
                )
            ]
            if trail is not None and len(trail) > 1
            else []
        )
        entities.append(
            SceneEntity(
                timestamp=ts,
                frame_id=frame,
                id=f'track/{t.id}',
                cylinders=[
                    CylinderPrimitive(
                        pose=_pose(x, y, height / 2),
                        size=Vector3(x=diameter, y=diameter, z=height),
                        bottom_scale=1.0,
                        top_scale=1.0,
                        color=colour,
                    )
                ],
                texts=[
                    TextPrimitive(
                        pose=_pose(x, y, height + 0.4),
                        billboard=True,
                        font_size=16.0,
                        scale_invariant=True,
                        color=WHITE,
                        text=str(t.id),
                    )
                ],
                lines=lines,
            )
        )
    return SceneUpdate(
        deletions=[SceneEntityDeletion(timestamp=ts, type=SceneEntityDeletionType.All)], entities=entities
    )
