"""Data classes shared by every dataset reader (internal convention, see ``geometry/camera.py``)."""

from dataclasses import dataclass, field

import numpy as np


class DatasetError(Exception):
    """A dataset folder is missing, malformed or inconsistent. The message says which file and why."""


@dataclass(frozen=True)
class BoundingBox:
    """Axis-aligned box in image pixels (pixel-centre convention); may extend past the image border."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @property
    def bottom_center(self) -> np.ndarray:
        """(2,) the foot point of a standing person: centre of the bottom edge."""
        return np.array([(self.xmin + self.xmax) / 2.0, self.ymax])


@dataclass(frozen=True)
class PersonAnnotation:
    """One annotated person in one frame.

    Attributes:
        person_id: identity, stable over the sequence.
        position_id: the dataset's own ground-grid cell id (kept so files round-trip exactly).
        world_xy: (2,) position in world metres, internal convention (from ``position_id``).
        boxes: view name -> box, only for the views where the person is visible.
    """

    person_id: int
    position_id: int
    world_xy: np.ndarray
    boxes: dict = field(default_factory=dict)


@dataclass(frozen=True)
class PlaneCorrespondences:
    """2-D/3-D correspondences of calibration markers in one view and frame.

    Attributes:
        marker_ids: (N,) int ids.
        image_uv: (N, 2) pixels, internal convention.
        world_xyz: (N, 3) world metres, internal convention.
    """

    marker_ids: np.ndarray
    image_uv: np.ndarray
    world_xyz: np.ndarray
