"""Training/evaluation samples from any MATRIX-format folder (real or simulated) for the BEV network."""

import cv2
import numpy as np
import torch

from matrix_core.bev.augment import AugmentConfig, augment_feat_H_grid, augment_view
from matrix_core.bev.calibration_sources import calibration_source
from matrix_core.bev.encoder import SmallEncoder
from matrix_core.bev.lifting import feat_H_grid
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.targets import bev_targets
from matrix_core.datasets import open_dataset

MEAN = np.array([0.485, 0.456, 0.406], np.float32)
STD = np.array([0.229, 0.224, 0.225], np.float32)
PAD_RGB = tuple(float(c) for c in MEAN * 255.0)     # augmentation padding: zero after normalise_rgb


def resize_rgb(bgr: np.ndarray, size: tuple) -> np.ndarray:
    """(H, W, 3) uint8 BGR -> (h, w, 3) uint8 RGB at ``size`` = (w, h) (what the image cache keeps)."""
    return cv2.cvtColor(cv2.resize(bgr, size, interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2RGB)


def normalise_rgb(rgb: np.ndarray) -> np.ndarray:
    """(h, w, 3) uint8 RGB -> (3, h, w) float32 normalised with the ImageNet mean/std."""
    return ((rgb.astype(np.float32) / 255.0 - MEAN) / STD).transpose(2, 0, 1)


def prepare_image(bgr: np.ndarray, size: tuple) -> np.ndarray:
    """(H, W, 3) uint8 BGR -> (3, h, w) float32 normalised RGB at ``size`` = (w, h)."""
    return normalise_rgb(resize_rgb(bgr, size))


def ground_truth_positions(dataset, frame: int) -> dict:
    """person id -> (2,) world metres: exact trajectories when the folder has them, else annotation cells."""
    pos = dataset.pedestrian_positions(frame) if hasattr(dataset, 'pedestrian_positions') else {}
    if pos:
        return {i: np.asarray(p)[:2] for i, p in pos.items()}
    return {a.person_id: np.asarray(a.world_xy)[:2] for a in dataset.annotations(frame)}


class BevFrames(torch.utils.data.Dataset):
    """Frames of one MATRIX folder as network inputs plus targets.

    Item ``k`` (``data[k]``, or ``data.sample(k, rng)`` augmented) is a dict: ``images`` (V, 3, h, w),
    ``feat_H_grid`` (V, 3, 3) float32, ``view_mask`` (V,) bool, the target arrays of :func:`bev_targets`,
    ``frame`` int, and ``prev_frame`` (the previous frame of the sequence, -1 for the first). Views missing
    in ``views``, and views the calibration source has no homography for in a frame (PnP failed,
    registration failed), are masked out for that frame.

    Args:
        root: MATRIX folder.
        settings: :class:`BevSettings` (grid, input size).
        frames: frames to use (default: all with images and calibration).
        calibration: a name in ``CALIBRATION_SOURCES``.
        views: views to use (default all); the others are masked.
        cache_images: keep resized images in memory (uint8; about 0.4 MB per view and frame at 480x272).
        calibration_dir: output folder of ``matrix-tracker calibrate``/``register`` for the ``pnp``/
            ``registration`` sources.
        augment: :class:`AugmentConfig` of a TRAINING sequence; images are augmented (after the cache,
            which keeps the clean resized images) only when it is enabled AND a generator is passed to
            :meth:`sample`/:meth:`inputs`, so ``data[k]`` and evaluation are never augmented.
    """

    def __init__(self, root, settings: BevSettings, frames=None, calibration: str = 'ground_truth', views=None,
                 cache_images: bool = True, calibration_dir=None, augment: AugmentConfig = None):
        self.dataset = open_dataset(root)
        self.settings = settings
        self.frames = tuple(frames) if frames is not None else tuple(self.dataset.frames)
        missing = set(self.frames) - set(self.dataset.frames)
        if missing:
            raise ValueError(f'{root}: frames {sorted(missing)[:5]} have no images/calibration')
        self.grid = settings.grid(self.dataset.area)
        self.calibration = calibration
        self.homography_of = calibration_source(calibration, self.dataset, self.frames, calibration_dir)
        self.views = tuple(self.dataset.views)
        self.use_views = set(views) if views else set(self.views)
        self.input_size = (settings.image_width, settings.image_height)
        self._cache = {} if cache_images else None
        self.stride = SmallEncoder.stride  # input pixels per feature pixel, as BevFusionNet.stride
        self.augment = augment if augment is not None and augment.enabled else None

    def __len__(self) -> int:
        return len(self.frames)

    def rgb(self, view: str, frame: int) -> np.ndarray:
        """(h, w, 3) uint8 RGB of one view at the input size (cached when ``cache_images``)."""
        key = (view, frame)
        if self._cache is not None and key in self._cache:
            return self._cache[key]
        rgb = resize_rgb(self.dataset.load_image(view, frame), self.input_size)
        if self._cache is not None:
            self._cache[key] = rgb      # uint8: a quarter of the memory of the float input
        return rgb

    def image(self, view: str, frame: int) -> np.ndarray:
        """(3, h, w) float32 normalised network input of one view."""
        return normalise_rgb(self.rgb(view, frame))

    def homographies(self, frame: int) -> np.ndarray:
        """(V, 3, 3) float32 ``feat_H_grid`` of every view at ``frame`` (zeros where the source has none)."""
        return self.homographies_and_availability(frame)[0]

    def homographies_and_availability(self, frame: int) -> tuple:
        """(feat_H_grid (V, 3, 3) float32, available (V,) bool) at ``frame``; a view without a homography
        from the calibration source gets zeros (nothing lies in front of it) and available False."""
        out, available = [], []
        for v in self.views:
            h = self.homography_of(v, frame)
            available.append(h is not None)
            out.append(np.zeros((3, 3)) if h is None else
                       feat_H_grid(h[0], self.grid.ground_H_grid, h[1], self.input_size, self.stride))
        return np.stack(out).astype(np.float32), np.array(available, dtype=bool)

    def inputs(self, frame: int, rng: np.random.Generator = None) -> dict:
        """Network inputs of one frame: ``images`` (V, 3, h, w), ``feat_H_grid`` (V, 3, 3), ``view_mask`` (V,).
        With ``rng`` and an enabled ``augment``, each view is augmented independently and its
        ``feat_H_grid`` follows its scale-and-crop."""
        H, available = self.homographies_and_availability(frame)
        mask = np.array([v in self.use_views for v in self.views]) & available
        images = np.zeros((len(self.views), 3, self.input_size[1], self.input_size[0]), np.float32)
        augment = self.augment if rng is not None else None
        for i, v in enumerate(self.views):
            if not mask[i]:
                continue
            rgb = self.rgb(v, frame)
            if augment is not None:
                rgb, aug_H_input = augment_view(rgb, augment, rng, PAD_RGB)
                H[i] = augment_feat_H_grid(H[i].astype(np.float64), aug_H_input, self.stride)
            images[i] = normalise_rgb(rgb)
        return {'images': torch.from_numpy(images), 'feat_H_grid': torch.from_numpy(H),
                'view_mask': torch.from_numpy(mask)}

    def __getitem__(self, k: int) -> dict:
        return self.sample(k)

    def sample(self, k: int, rng: np.random.Generator = None) -> dict:
        """Item ``k``; augmented with ``rng`` when ``augment`` is enabled (see :meth:`inputs`)."""
        frame = self.frames[k]
        prev = self.frames[k - 1] if k > 0 else -1
        pos = ground_truth_positions(self.dataset, frame)
        prev_pos = ground_truth_positions(self.dataset, prev) if prev >= 0 else None
        targets = bev_targets(self.grid, pos, prev_pos, self.settings.heatmap_sigma_m)
        return {**self.inputs(frame, rng), 'frame': frame, 'prev_frame': prev,
                **{name: torch.from_numpy(arr) for name, arr in targets.items()}}
