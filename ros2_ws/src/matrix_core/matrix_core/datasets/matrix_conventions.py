"""Every quirk of the MATRIX file format, converted in this one module (and nowhere else).

MATRIX files (as written by the original AirSim/Unreal generator, measured in
``shared/matrix_sample/README.md``) use these conventions:

- world: metres, z up, but LEFT-handed (Unreal axes): seen from above, +x to +y turns clockwise;
- calibration (``rvec``, ``tvec``, ``K``) projects into a horizontally MIRRORED image:
  ``u_image = W - u_projected``;
- pixel coordinates in files (annotation boxes, ``matchings/Planes`` 2-D points) are raw (unmirrored)
  image pixels with the pixel-CORNER origin, i.e. 0.5 px off OpenCV's pixel-centre convention;
- ``positionID = gx + 300 * gy`` with ``gx = floor(10 x)``, ``gy = floor(10 y)`` (0.1 m cells);
- ``matchings/Planes/3d.txt`` is in centimetres in a frame shifted by (-7.5, -7.5, -5) m;
- the original generator's ``matchings/Planes`` files of frame 0000 are bogus (leftover of another run).

Internally (see ``matrix_core.geometry.camera``) the world is right-handed and images are never mirrored.
The mapping used here is the README's "equivalent right-handed form":

- ``world_internal = M @ world_file`` with ``M = diag(1, -1, 1)`` (negate y);
- ``R_internal = N @ R_file @ M``, ``t_internal = N @ t_file`` with ``N = diag(-1, 1, 1)`` (mirror camera x);
- ``K_internal = F @ K_file @ N`` where ``F`` mirrors pixel x (``u -> W - u``) and moves both axes from
  pixel-corner to pixel-centre coordinates (``-0.5``); distortion ``p2`` changes sign under the mirror;
- ``pixel_internal = pixel_file - 0.5`` for file pixel coordinates (they are already unmirrored).

These reproduce the stored projections exactly (tested on the real sample).
"""

import numpy as np

from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.site.shipped import matrix_site

# Axis flips: N mirrors the camera x axis, M negates the world y axis (both are their own inverse).
N = np.diag([-1.0, 1.0, 1.0])
M = np.diag([1.0, -1.0, 1.0])

PIXEL_OFFSET = 0.5  # file pixels (corner origin) minus internal pixels (centre origin)
POSITION_GRID_COLS = 300
POSITION_CELL_M = 0.1
PLANES_3D_OFFSET_M = np.array([7.5, 7.5, 5.0])  # added after converting Planes/3d.txt from cm to m
ORIGINAL_BOGUS_PLANE_FRAMES = (0,)  # frames whose Planes 2-D files the original generator got wrong


def _pixel_flip(width: int) -> np.ndarray:
    """(3, 3) F: file-convention projected pixels -> internal pixels (mirror x, corner -> centre)."""
    return np.array([[-1.0, 0.0, width - PIXEL_OFFSET], [0.0, 1.0, -PIXEL_OFFSET], [0.0, 0.0, 1.0]])


def camera_from_file(K_file, dist_file, rvec_file, tvec_file, width: int, height: int) -> Camera:
    """Build an internal :class:`Camera` from MATRIX calibration values.

    Args:
        K_file: (3, 3) ``camera_matrix`` of ``intr_*.xml``.
        dist_file: (5,) ``distortion_coefficients`` (k1, k2, p1, p2, k3).
        rvec_file, tvec_file: (3,) ``rvec``/``tvec`` of ``extr_*.xml`` (file world -> file camera, metres).
        width, height: image size in pixels (the mirror is about the image width).
    """
    import cv2

    R_file, _ = cv2.Rodrigues(np.asarray(rvec_file, dtype=np.float64).reshape(3, 1))
    R = N @ R_file @ M
    t = N @ np.reshape(tvec_file, 3)
    K = _pixel_flip(width) @ np.asarray(K_file, dtype=np.float64) @ N
    d = np.reshape(np.asarray(dist_file, dtype=np.float64), -1).copy()
    d = np.concatenate([d, np.zeros(max(0, 5 - len(d)))])[:5]
    d[3] = -d[3]
    return Camera(K, pose_matrix(R, t), width, height, d)


def camera_to_file(camera: Camera) -> dict:
    """Inverse of :func:`camera_from_file`: MATRIX file values of an internal camera.

    Returns:
        dict with ``camera_matrix`` (3, 3), ``distortion_coefficients`` (1, 5), ``rvec`` (3, 1),
        ``tvec`` (3, 1), ready for :func:`matrix_core.datasets.opencv_xml.write_matrices`.
    """
    import cv2

    R_file = N @ camera.R @ M
    t_file = N @ camera.t
    K_file = np.linalg.inv(_pixel_flip(camera.width)) @ camera.K @ N
    d = camera.dist.copy()
    d[3] = -d[3]
    return {
        'camera_matrix': K_file,
        'distortion_coefficients': d.reshape(1, 5),
        'rvec': cv2.Rodrigues(R_file)[0].reshape(3, 1),
        'tvec': t_file.reshape(3, 1),
    }


def world_from_file(points_file) -> np.ndarray:
    """(N, 3) or (N, 2) file world metres -> internal world metres (negate y)."""
    pts = np.array(points_file, dtype=np.float64, ndmin=2)
    pts[:, 1] = -pts[:, 1]
    return pts


world_to_file = world_from_file  # negating y is its own inverse


def ground_homography_from_file(ground_H_img_file) -> np.ndarray:
    """(3, 3) homography raw file image pixels -> file world ground (x, y) metres (as ``matrix-tracker
    register`` writes ``H_img_to_ground``) -> internal image pixels -> internal world ground metres."""
    file_pix_H_pix = np.array([[1.0, 0.0, PIXEL_OFFSET], [0.0, 1.0, PIXEL_OFFSET], [0.0, 0.0, 1.0]])
    return M @ np.asarray(ground_H_img_file, dtype=np.float64) @ file_pix_H_pix


def area_from_file(x_range, y_range) -> tuple:
    """File-frame area ((x0, x1), (y0, y1)) -> internal (x_min, y_min, x_max, y_max) metres."""
    (x0, x1), (y0, y1) = x_range, y_range
    return (float(x0), 0.0 - float(y1), float(x1), 0.0 - float(y0))


def area_to_file(area) -> list:
    """Internal (x_min, y_min, x_max, y_max) -> file-frame [[x0, x1], [y0, y1]] metres."""
    x_min, y_min, x_max, y_max = area
    return [[float(x_min), float(x_max)], [0.0 - float(y_max), 0.0 - float(y_min)]]


# The MATRIX square (0, -30, 30, 0): internal (x_min, y_min, x_max, y_max) metres, read from the shipped
# MATRIX site file (matrix_core/site/sites/matrix.yaml). The default area of every component (register, fuse,
# graph monitor, simulator); it is also the extent of the positionID grid (300 x 300 cells of 0.1 m), so
# simulated areas must lie inside it.
MATRIX_AREA = matrix_site().area
ORIGINAL_AREA_FILE_XY = tuple(tuple(r) for r in area_to_file(MATRIX_AREA))  # pedestrian area, file metres


def pixels_from_file(uv_file) -> np.ndarray:
    """(N, 2) pixel coordinates read from MATRIX files -> internal pixel-centre coordinates."""
    return np.array(uv_file, dtype=np.float64, ndmin=2) - PIXEL_OFFSET


def pixels_to_file(uv) -> np.ndarray:
    """(N, 2) internal pixel coordinates -> MATRIX file pixel coordinates."""
    return np.array(uv, dtype=np.float64, ndmin=2) + PIXEL_OFFSET


def box_from_file(xmin, ymin, xmax, ymax):
    """Annotation box in file pixels -> (xmin, ymin, xmax, ymax) internal pixels, or None if invisible.

    Invisible views have all four values -1 (visible boxes may have negative coordinates).
    """
    if xmin == -1 and ymin == -1 and xmax == -1 and ymax == -1:
        return None
    return tuple(float(v) - PIXEL_OFFSET for v in (xmin, ymin, xmax, ymax))


def box_to_file(xmin, ymin, xmax, ymax) -> dict:
    """Internal box -> the integer fields of an annotation view entry."""
    vals = [int(round(v + PIXEL_OFFSET)) for v in (xmin, ymin, xmax, ymax)]
    return dict(zip(('xmin', 'ymin', 'xmax', 'ymax'), vals))


INVISIBLE_BOX = {'xmin': -1, 'ymin': -1, 'xmax': -1, 'ymax': -1}


def position_id_to_world(position_id: int) -> np.ndarray:
    """positionID -> (2,) internal world metres of the grid point the original generator used."""
    gx = position_id % POSITION_GRID_COLS
    gy = position_id // POSITION_GRID_COLS
    return world_from_file([[gx * POSITION_CELL_M, gy * POSITION_CELL_M]])[0]


def world_to_position_id(xy) -> int:
    """(2,) internal world metres -> positionID (cell containing the point)."""
    x_file, y_file = world_to_file([xy])[0][:2]
    # A tiny epsilon keeps points exactly on a cell boundary from falling one cell short by rounding.
    gx = int(np.floor(x_file / POSITION_CELL_M + 1e-9))
    gy = int(np.floor(y_file / POSITION_CELL_M + 1e-9))
    if not (0 <= gx < POSITION_GRID_COLS and gy >= 0):
        raise ValueError(f'position {xy} is outside the MATRIX position grid')
    return gx + POSITION_GRID_COLS * gy


def planes_3d_from_file(xyz_cm) -> np.ndarray:
    """(N, 3) ``Planes/3d.txt`` centimetres (shifted frame) -> internal world metres."""
    return world_from_file(np.asarray(xyz_cm, dtype=np.float64) / 100.0 + PLANES_3D_OFFSET_M)


def planes_3d_to_file(xyz) -> np.ndarray:
    """(N, 3) internal world metres -> ``Planes/3d.txt`` centimetres."""
    return (world_to_file(xyz) - PLANES_3D_OFFSET_M) * 100.0


def view_name(drone_number: int) -> str:
    """1-based drone number -> view name used throughout the code ('D1')."""
    return f'D{drone_number}'


MATRIX_VIEWS = matrix_site().drone_names  # the eight drones of the MATRIX scenes, D1..D8


def drone_number(view: str) -> int:
    """View name ('D3') -> 1-based drone number (3). JSON ``viewNum`` is this minus one."""
    if not (view.startswith('D') and view[1:].isdigit()):
        raise ValueError(f'not a MATRIX view name: {view!r}')
    return int(view[1:])
