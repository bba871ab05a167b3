"""The reference a drone's frames are registered to: the configured reference image with its calibration,
and optionally a key frame chained to it (re-keying).

Features are extracted once per reference / key frame and cached here. Only ground features are kept:
the reference's through :func:`~matrix_core.register.ground_mask.ground_pixels`, a key frame's by mapping
them into the reference image first.
"""

from dataclasses import dataclass

import numpy as np

from matrix_core.geometry.camera import Camera
from matrix_core.geometry.homography import apply_homography
from matrix_core.register.features import Features
from matrix_core.register.gate import ground_polygon
from matrix_core.register.ground_mask import ground_pixels, visible_ground_grid


@dataclass(frozen=True)
class KeyFrame:
    """A well-registered earlier frame used as an intermediate reference.

    Attributes:
        key_id: e.g. 'key:17'; features: its ground features; key_to_ref: (3, 3) key pixels -> reference pixels.
    """

    key_id: str
    features: Features
    key_to_ref: np.ndarray


class Reference:
    """Reference image of one drone: calibration, cached ground features, ground polygon for the gate."""

    def __init__(
        self,
        reference_id: str,
        camera: Camera,
        features: Features,
        area,
        ground_only: bool = True,
        margin_m: float = 0.0,
        boxes=(),
    ):
        self.reference_id = reference_id
        self.camera = camera
        self.area = area
        self.ground_only = ground_only
        self.margin_m = margin_m
        self.boxes = boxes
        self.features = self._ground_features(features, features.xy)
        if not len(self.features):
            raise ValueError(f'{reference_id}: no reference feature lies on the ground (check the calibration)')
        world = visible_ground_grid(camera, area, 1.0, boxes)
        if len(world) < 3:
            raise ValueError(f'{reference_id}: the reference camera sees no ground of the area {area}')
        self.polygon = ground_polygon(camera.img_H_ground(), world)

    def _ground_features(self, features: Features, xy_in_ref: np.ndarray) -> Features:
        if not self.ground_only:
            return features
        inside = self.camera.in_image(np.nan_to_num(xy_in_ref, nan=-1e9))
        keep = np.zeros(len(features), dtype=bool)
        keep[inside] = ground_pixels(self.camera, xy_in_ref[inside], self.area, self.margin_m, self.boxes)
        return features.subset(keep)

    def make_key(self, key_id: str, features: Features, key_to_ref: np.ndarray) -> KeyFrame:
        """A key frame from a registered frame's (unmasked) features and its ``key_to_ref``."""
        xy_ref = apply_homography(key_to_ref, features.xy)
        return KeyFrame(key_id, self._ground_features(features, xy_ref), key_to_ref)
