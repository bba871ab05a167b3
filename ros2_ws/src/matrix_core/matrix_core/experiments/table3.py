"""What can be run of the paper's Table III (stationary datasets) here: Wildtrack and MultiviewX cannot be
downloaded, but the real MultiviewX sample in ``../shared/multiviewx_sample`` (6 cameras, its README) can
be read. Its images and annotation files do not correspond frame by frame (its README), so no detection can
be scored on it; what it does check is the reader's geometry: every annotated ground position, projected
with the reader's camera, should land on the bottom centre of that person's annotated box."""

from pathlib import Path

import numpy as np

from matrix_core.locations import shared_dir

IMAGE_SIZE = (1920, 1080)


def shared_path(spec: str) -> Path:
    """``shared:NAME`` -> ``$MATRIX_SHARED/NAME`` (:func:`matrix_core.locations.shared_dir`); other strings are
    plain paths."""
    if not spec.startswith('shared:'):
        return Path(spec)
    return shared_dir() / spec.split(':', 1)[1]


def _inside(box, width: int, height: int) -> bool:
    """Boxes touching the image border have a cut foot or side (left out, as in the sample's README)."""
    return box.xmin > 0 and box.ymin > 0 and box.xmax < width - 1 and box.ymax < height - 1


def foot_point_agreement(root) -> dict:
    """Per view of a static-rig dataset (Wildtrack/MultiviewX reader): distance in pixels between each
    annotated position projected on the ground (z = 0) and the bottom centre of its annotated box, over
    every annotated frame (boxes touching the border excluded).

    Returns ``{'format', 'frames', 'views': {view: {'n', 'behind_camera' (positions projecting behind the
    camera: NaN, left out of the statistics), 'median_px', 'p90_px', 'camera_height_m', 'tilt_deg'}}}``.
    """
    from matrix_core.datasets import open_dataset

    ds = open_dataset(root)
    views = {}
    for view in ds.views:
        cam = ds.camera(view, 0)
        feet, boxes = [], []
        for frame in ds.annotated_frames:
            for person in ds.annotations(frame):
                box = person.boxes.get(view)
                if box is not None and _inside(box, *IMAGE_SIZE):
                    feet.append(person.world_xy)
                    boxes.append(box.bottom_center)
        if not feet:
            views[view] = {'n': 0, 'median_px': None, 'p90_px': None}
            continue
        uv = cam.project(np.c_[np.asarray(feet, float), np.zeros(len(feet))])
        error = np.linalg.norm(uv - np.asarray(boxes, float), axis=1)
        views[view] = {
            'n': int(len(error)),
            'behind_camera': int(np.isnan(error).sum()),
            'median_px': float(np.nanmedian(error)),
            'p90_px': float(np.nanpercentile(error, 90)),
            'camera_height_m': float(cam.center[2]),
            'tilt_deg': float(cam.tilt_deg),
        }
    return {'format': type(ds).__name__, 'frames': len(ds.annotated_frames), 'views': views}
