"""Image-plane outputs: where each fused track appears in each drone's image, with its fused identity.

A track at ground position (x, y) is modelled as an upright cylinder standing on z = 0 (radius
``person_radius_m``, height ``person_height_m``). Its image box is the bounding box of the projected outline
(two circles of ``OUTLINE_POINTS`` points, at the feet and at the head), down to the projected foot point
(``bottom_at_foot``: how MATRIX and the simulator draw their annotation boxes), clipped to the image.

Visibility rule (a track is REPORTED in a view when all hold):
    1. the whole cylinder is in front of the camera (every outline point has positive depth);
    2. it is in the image: at least ``min_in_image`` of its unclipped box's area lies inside the image
       (MATRIX annotates people partly out of the image, e.g. with their feet below its edge);
    3. it is not hidden by the scene's obstacles: the exact segment-box test
       (:func:`~matrix_core.geometry.occlusion.segments_blocked`) from the camera centre to the cylinder's
       axis is clear at every height of ``visibility_heights_m`` (the simulator's line-of-sight heights).
A reported box is marked ``occluded`` (still reported) when more than ``person_occlusion`` of its area is
covered by the union of the boxes of reported people nearer the camera (nearer: smaller distance from the
camera centre to the track's foot point).

Pixels: OpenCV pixel centres on the unmirrored image; a box is ``x_min y_min x_max y_max`` clipped to
[-0.5, w - 0.5] x [-0.5, h - 0.5] (the image's outer edges).
"""

from dataclasses import dataclass, field

import cv2
import numpy as np

from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.geometry.homography import implied_camera
from matrix_core.geometry.occlusion import as_boxes, segments_blocked
from matrix_core.reference_size import REFERENCE_WIDTH
from matrix_core.register.scene import scene_from_meta
from matrix_core.register.settings import MATRIX_BLOCK
from matrix_core.settings import Settings

OUTLINE_POINTS = 16  # points per circle of the cylinder's outline


@dataclass
class ImageBoxSettings(Settings):
    """The person model and the visibility rule of the image boxes (module docstring)."""

    person_radius_m: float = field(
        default=0.25,
        metadata={
            'help': "radius of the person cylinder (m); MATRIX's annotation boxes use 0.16 m, but a wider box "
            'tolerates the BEV position error (about 0.1 m) better: offline 2D precision / recall on the real '
            'sample 91.7 / 88.1 percent at 0.25 m, 88.2 / 84.8 percent at 0.16 m'
        },
    )
    person_height_m: float = field(default=1.75, metadata={'help': 'height of the person cylinder (m)'})
    bottom_at_foot: bool = field(
        default=True,
        metadata={
            'help': "the box runs from the cylinder's top down to the projected foot point (MATRIX's and the "
            "simulator's annotation convention); false: to the bottom of the projected outline"
        },
    )
    visibility_heights_m: list[float] = field(
        default_factory=lambda: [0.05, 0.9],
        metadata={
            'help': 'a person is hidden by an obstacle when the ray to its axis at any of these heights is blocked'
        },
    )
    min_in_image: float = field(
        default=0.5,
        metadata={'help': "a person is reported when at least this fraction of its box's area is inside the image"},
    )
    person_occlusion: float = field(
        default=0.7,
        metadata={
            'help': 'a box more than this fraction covered by boxes of people nearer the camera is marked occluded'
        },
    )
    obstacle_boxes: list[float] = field(
        default_factory=lambda: list(MATRIX_BLOCK),
        metadata={
            'help': 'obstacles hiding people, groups of 5 numbers x0 y0 x1 y1 height (internal world metres); '
            "default: the MATRIX central block (a simulated folder's own come from its meta)"
        },
    )

    def check(self) -> None:
        if self.person_radius_m <= 0 or self.person_height_m <= 0:
            raise ValueError('person_radius_m and person_height_m must be positive')
        if not (0.0 < self.person_occlusion <= 1.0 and 0.0 < self.min_in_image <= 1.0):
            raise ValueError('person_occlusion and min_in_image must be in (0, 1]')
        as_boxes(self.obstacle_boxes)


@dataclass(frozen=True)
class ImageBox:
    """One track seen in one view. ``box``: (4,) x_min y_min x_max y_max pixels (clipped); ``distance_m``:
    camera centre to the foot point; ``occluded``: covered by nearer people (module docstring)."""

    track_id: int
    score: float
    box: np.ndarray
    distance_m: float
    occluded: bool = False


def obstacles_from_meta(meta: dict, default) -> list:
    """The obstacle boxes a dataset's meta states (simulated folders: block and pillars), else ``default``."""
    scene = scene_from_meta(meta)
    return list(default) if scene is None else list(scene[0])


def implied_view_camera(implied, size: tuple) -> Camera:
    """A :class:`Camera` (no distortion) from an ``ImpliedCamera`` (``Registration.implied_camera(K)``) and
    the image (w, h): the camera the registration homography implies."""
    return Camera(implied.K, pose_matrix(implied.R, implied.t), int(size[0]), int(size[1]))


def camera_from_ground_homography(img_H_ground, K, size: tuple) -> Camera:
    """The camera a (3, 3) ground -> pixel homography implies with intrinsics ``K`` (3, 3), image (w, h)."""
    return implied_view_camera(implied_camera(np.asarray(K, dtype=np.float64), img_H_ground), size)


def cylinder_outline(xy, radius: float, height: float) -> np.ndarray:
    """(N, 2 * OUTLINE_POINTS, 3) world points of the base and top circles of cylinders at (N, 2) ``xy``."""
    a = np.linspace(0.0, 2 * np.pi, OUTLINE_POINTS, endpoint=False)
    ring = np.stack([radius * np.cos(a), radius * np.sin(a)], axis=1)  # (P, 2)
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 1, 2)
    pts = np.concatenate([xy + ring, xy + ring], axis=1)  # (N, 2P, 2)
    z = np.concatenate([np.zeros(OUTLINE_POINTS), np.full(OUTLINE_POINTS, height)])
    return np.concatenate([pts, np.broadcast_to(z[None, :, None], pts.shape[:2] + (1,))], axis=2)


def clip_box(box, width: int, height: int) -> np.ndarray:
    """(..., 4) boxes clipped to the image's outer edges (pixel centres: [-0.5, w - 0.5])."""
    box = np.array(box, dtype=np.float64)
    box[..., 0::2] = np.clip(box[..., 0::2], -0.5, width - 0.5)
    box[..., 1::2] = np.clip(box[..., 1::2], -0.5, height - 0.5)
    return box


def box_area(boxes) -> np.ndarray:
    """(N,) areas of (N, 4) boxes (0 for empty ones)."""
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    return np.clip(b[:, 2] - b[:, 0], 0, None) * np.clip(b[:, 3] - b[:, 1], 0, None)


def covered_fraction(box, others) -> float:
    """Fraction of ``box`` (4,) covered by the union of ``others`` (K, 4), exact (coordinate compression)."""
    others = np.asarray(others, dtype=np.float64).reshape(-1, 4)
    area = box_area(box)[0]
    if area <= 0 or not len(others):
        return 0.0
    o = np.column_stack(
        [
            np.maximum(others[:, 0], box[0]),
            np.maximum(others[:, 1], box[1]),
            np.minimum(others[:, 2], box[2]),
            np.minimum(others[:, 3], box[3]),
        ]
    )
    o = o[(o[:, 2] > o[:, 0]) & (o[:, 3] > o[:, 1])]
    if not len(o):
        return 0.0
    xs, ys = np.unique(o[:, 0::2]), np.unique(o[:, 1::2])
    cx, cy = (xs[:-1] + xs[1:]) / 2, (ys[:-1] + ys[1:]) / 2
    inside = (
        (cx[None, :, None] > o[:, 0, None, None])
        & (cx[None, :, None] < o[:, 2, None, None])
        & (cy[None, None, :] > o[:, 1, None, None])
        & (cy[None, None, :] < o[:, 3, None, None])
    ).any(axis=0)
    cells = np.diff(xs)[:, None] * np.diff(ys)[None, :]
    return float((cells * inside).sum() / area)


def image_boxes(camera: Camera, track_ids, xy, scores, settings: ImageBoxSettings = None) -> list:
    """The :class:`ImageBox` of every track ``camera`` sees (the module's visibility rule), nearest first.

    Args:
        camera: the view's camera of the frame.
        track_ids: (N,) ints; xy: (N, 2) ground positions, world metres; scores: (N,) floats.
    """
    s = settings or ImageBoxSettings()
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    n = len(xy)
    if n == 0:
        return []
    outline = cylinder_outline(xy, s.person_radius_m, s.person_height_m).reshape(-1, 3)
    in_front = (camera.depth(outline) > 0).reshape(n, -1).all(axis=1)
    uv = np.nan_to_num(camera.project(outline).reshape(n, -1, 2))  # behind the camera: dropped below
    full = np.concatenate([uv.min(axis=1), uv.max(axis=1)], axis=1)
    foot = np.column_stack([xy, np.zeros(n)])
    if s.bottom_at_foot:
        full[:, 3] = np.nan_to_num(camera.project(foot)[:, 1])
    boxes = clip_box(full, camera.width, camera.height)
    with np.errstate(invalid='ignore', divide='ignore'):
        keep = in_front & (box_area(boxes) >= s.min_in_image * box_area(full)) & (box_area(boxes) > 0)
    for z in s.visibility_heights_m:
        keep &= ~segments_blocked(camera.center, np.column_stack([xy, np.full(n, z)]), s.obstacle_boxes)
    idx = np.flatnonzero(keep)
    if not len(idx):
        return []
    boxes = boxes[idx]
    dist = np.linalg.norm(foot[idx] - camera.center, axis=1)
    order = np.argsort(dist, kind='stable')
    ids, sc = np.asarray(track_ids).reshape(-1), np.asarray(scores, dtype=np.float64).reshape(-1)
    # The union of the nearer boxes covers at most the sum of their overlaps: only boxes whose sum passes the
    # threshold need the exact union (most boxes in a crowd overlap little).
    near = boxes[order]
    overlap = np.clip(
        np.minimum(near[:, None, 2], near[None, :, 2]) - np.maximum(near[:, None, 0], near[None, :, 0]), 0, None
    ) * np.clip(
        np.minimum(near[:, None, 3], near[None, :, 3]) - np.maximum(near[:, None, 1], near[None, :, 1]), 0, None
    )
    maybe = np.tril(overlap, -1).sum(axis=1) > s.person_occlusion * box_area(near)
    out = []
    for rank, k in enumerate(order):
        occluded = maybe[rank] and covered_fraction(boxes[k], boxes[order[:rank]]) > s.person_occlusion
        out.append(ImageBox(int(ids[idx[k]]), float(sc[idx[k]]), boxes[k], float(dist[k]), bool(occluded)))
    return out


def id_colour(track_id: int) -> tuple:
    """A distinct, stable BGR colour per id (golden-ratio hues, as the RViz markers)."""
    hue = int((int(track_id) * 0.618034) % 1.0 * 179)
    return tuple(int(c) for c in cv2.cvtColor(np.uint8([[[hue, 255, 255]]]), cv2.COLOR_HSV2BGR)[0, 0])


def draw_image_boxes(image: np.ndarray, boxes, ids, occluded=None, thickness: int = 4) -> np.ndarray:
    """A copy of the (H, W, 3) BGR ``image`` with (N, 4) ``boxes`` and their ids drawn, a colour per id;
    occluded boxes (N,) bool are drawn thin."""
    img = image.copy()
    scale = max(img.shape[1] / REFERENCE_WIDTH, 0.3)
    boxes = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    for k, (i, b) in enumerate(zip(ids, boxes)):
        colour = id_colour(i)
        p0, p1 = tuple(int(round(c)) for c in b[:2]), tuple(int(round(c)) for c in b[2:])
        thin = occluded is not None and occluded[k]
        cv2.rectangle(img, p0, p1, colour, max(1, round((1 if thin else thickness) * scale)))
        cv2.putText(
            img,
            str(int(i)),
            (p0[0], max(p0[1] - int(8 * scale), int(30 * scale))),
            cv2.FONT_HERSHEY_SIMPLEX,
            1.4 * scale,
            colour,
            max(1, round(thickness * scale)),
        )
    return img
