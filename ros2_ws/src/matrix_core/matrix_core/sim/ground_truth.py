"""Ground truth of one frame and view: MATRIX-style annotation boxes, visibility, marker correspondences,
and the true ground homography / pose.

Annotation boxes follow MATRIX exactly: a cylinder of radius 0.16 m and height 1.8 m standing on the
person's position is projected; the box spans the projected cylinder horizontally and runs from its top to
the projected foot point vertically. Unlike MATRIX (which used the positionID grid point) the cylinder
stands on the TRUE position, so a box's bottom centre is the person's projected foot point (within the
perspective asymmetry of the cylinder, a few pixels).

Convention: internal pixels and world metres; ``img_H_ground`` maps ground (x, y, 1) to pixels.
"""

import numpy as np

from matrix_core.datasets.types import BoundingBox

CYLINDER_RADIUS_M = 0.16
CYLINDER_HEIGHT_M = 1.8
BOARD_PLANE_Z = 0.1  # height of the checkerboard plane in the shipped configs (as in MATRIX)
_ANGLES = np.linspace(0.0, 2 * np.pi, 24, endpoint=False)


def annotation_box(camera, xy) -> BoundingBox:
    """Box of the projected 0.16 m x 1.8 m cylinder standing at ``xy`` (2,) metres (internal pixels)."""
    ring = np.stack([xy[0] + CYLINDER_RADIUS_M * np.cos(_ANGLES), xy[1] + CYLINDER_RADIUS_M * np.sin(_ANGLES)], axis=1)
    pts = np.concatenate([np.c_[ring, np.zeros(len(ring))], np.c_[ring, np.full(len(ring), CYLINDER_HEIGHT_M)]])
    uv = camera.project(pts)
    foot = camera.project(np.array([[xy[0], xy[1], 0.0]]))[0]
    return BoundingBox(float(uv[:, 0].min()), float(uv[:, 1].min()), float(uv[:, 0].max()), float(foot[1]))


def visible_markers(camera, marker_ids, marker_xyz, boxes, rays_blocked) -> tuple:
    """Markers whose projection is inside the image and not hidden by a box (people may cover them):
    ((M,) ids, (M, 2) internal pixels)."""
    if len(marker_ids) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
    uv = camera.project(marker_xyz)
    ok = np.isfinite(uv).all(axis=1)
    ok[ok] = camera.in_image(uv[ok])
    ok[ok] = ~rays_blocked(camera.center, marker_xyz[ok], boxes)
    return np.asarray(marker_ids)[ok], uv[ok]


def view_truth(camera, drone=None) -> dict:
    """JSON-ready per-view truth: ``img_H_ground`` (z = 0) and ``img_H_boards`` (z = 0.1) normalised to
    H[2, 2] = 1, ``world_T_cam``,
    camera centre, and the drone's position/velocity (metres, m/s) when given."""
    ground, boards = camera.img_H_ground(0.0), camera.img_H_ground(BOARD_PLANE_Z)
    out = {
        'img_H_ground': (ground / ground[2, 2]).tolist(),
        'img_H_boards': (boards / boards[2, 2]).tolist(),
        'world_T_cam': camera.world_T_cam.tolist(),
        'camera_center': camera.center.tolist(),
        'tilt_deg': camera.tilt_deg,
    }
    if drone is not None:
        out['drone_position'] = [float(v) for v in drone.position]
        out['drone_velocity'] = [float(v) for v in drone.velocity]
        out['gimbal_yaw_pitch_roll_rad'] = [float(drone.yaw), float(drone.pitch + drone.body_pitch), float(drone.roll)]
    return out
