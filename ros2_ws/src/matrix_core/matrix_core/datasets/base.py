"""The interface every multi-view dataset reader offers (MATRIX, Wildtrack, MultiviewX)."""

from abc import ABC, abstractmethod
from functools import cached_property
from pathlib import Path

import cv2
import numpy as np

from matrix_core.datasets.types import DatasetError
from matrix_core.encoded_images import CorruptImage, decode_image
from matrix_core.geometry.camera import Camera

IMAGE_EXTENSIONS = ('.png', '.jpg', '.jpeg')


def find_image(folder: Path, stem: str) -> Path:
    """The image file ``folder/stem.{png,jpg,jpeg}``; raises :class:`DatasetError` if there is none."""
    for ext in IMAGE_EXTENSIONS:
        path = folder / (stem + ext)
        if path.is_file():
            return path
    raise DatasetError(f'no image {stem}.png/.jpg in {folder}')


def image_size(path: Path) -> tuple:
    """(width, height) of an image file, read from its header only."""
    from PIL import Image

    try:
        with Image.open(path) as im:
            return im.size
    except Exception as exc:  # PIL raises many types for corrupt files
        raise DatasetError(f'cannot read image header of {path}: {exc}') from exc


def numbered_stems(folder: Path, suffixes=IMAGE_EXTENSIONS) -> list:
    """Sorted integer frame numbers of files named like ``0012.png`` in ``folder``."""
    return sorted(int(p.stem) for p in folder.iterdir() if p.suffix.lower() in suffixes and p.stem.isdigit())


def read_image(path) -> np.ndarray:
    """(H, W, 3) uint8 BGR image of a file; :class:`DatasetError` naming the file if it cannot be read, is cut
    short (``matrix_core.encoded_images``: a decoder alone takes half a JPEG for an image) or cannot be
    decoded."""
    try:
        return decode_image(Path(path).read_bytes(), cv2.IMREAD_COLOR)
    except (OSError, CorruptImage) as exc:
        raise DatasetError(f'cannot decode image {path}: {exc}') from exc


class MultiviewDataset(ABC):
    """A synchronised multi-camera pedestrian dataset, everything in the internal convention.

    Convention: world metres (right-handed, z up), pixel-centre unmirrored image pixels, see
    ``matrix_core.geometry.camera``. Views are named by strings ('D1', 'C1', ...), frames by integers.
    """

    format_name = 'abstract'

    def __init__(self, root):
        self.root = Path(root)
        if not self.root.is_dir():
            raise DatasetError(f'dataset folder not found: {self.root}')

    @property
    @abstractmethod
    def views(self) -> tuple:
        """View names, in the dataset's camera order."""

    @property
    @abstractmethod
    def frames(self) -> tuple:
        """Frame numbers that have images for every view."""

    def select_views(self, views=()) -> list:
        """``views`` (all when empty), checked: :class:`DatasetError` names those the dataset does not have."""
        unknown = set(views) - set(self.views)
        if unknown:
            raise DatasetError(f'views {sorted(unknown)} not in {self.root} (it has {list(self.views)})')
        return list(views) or list(self.views)

    def select_frames(self, max_frames: int = 0) -> list:
        """The first ``max_frames`` frames (all when 0); :class:`DatasetError` for a negative count (never a
        Python slice from the end)."""
        if max_frames < 0:
            raise DatasetError(f'max_frames must be >= 0 (0 = all), got {max_frames}')
        return list(self.frames)[: max_frames or None]

    @abstractmethod
    def image_path(self, view: str, frame: int) -> Path:
        """Path of the image of ``view`` at ``frame``."""

    @abstractmethod
    def camera(self, view: str, frame: int) -> Camera:
        """Calibration of ``view`` at ``frame``."""

    @abstractmethod
    def annotations(self, frame: int) -> list:
        """:class:`PersonAnnotation` list of ``frame`` (empty when the frame has no annotation file)."""

    @abstractmethod
    def position_to_world(self, position_id: int) -> np.ndarray:
        """The dataset's ground-grid id -> (2,) world metres."""

    @property
    @abstractmethod
    def area(self) -> tuple:
        """(x_min, y_min, x_max, y_max) of the walkable area in world metres."""

    @property
    def incomplete_frames(self) -> dict:
        """frame -> why a frame some view has files of is not in :attr:`frames` (readers that can tell)."""
        return {}

    @property
    def annotated_frames(self) -> tuple:
        """Frame numbers that have an annotation file."""
        return ()

    @cached_property
    def image_size(self) -> tuple:
        """(width, height) of the images (of the first view and frame)."""
        if not self.frames:
            raise DatasetError(f'{self.root}: no frames')
        return image_size(self.image_path(self.views[0], self.frames[0]))

    def view_index(self, view: str) -> int:
        """0-based index of ``view`` (the ``viewNum`` of annotation files)."""
        try:
            return self.views.index(view)
        except ValueError:
            raise DatasetError(f'unknown view {view!r}; views are {self.views}') from None

    def load_image(self, view: str, frame: int) -> np.ndarray:
        """(H, W, 3) uint8 BGR image; raises :class:`DatasetError` if unreadable."""
        return read_image(self.image_path(view, frame))
