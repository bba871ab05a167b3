"""A short human-readable summary of any dataset folder (``matrix-tracker info``)."""

import numpy as np

from matrix_core.datasets.base import MultiviewDataset


def _span(values) -> str:
    values = np.asarray(values, dtype=np.float64)
    return f'{values.min():.2f} .. {values.max():.2f}' if values.size else 'n/a'


def summarize(ds: MultiviewDataset) -> dict:
    """Facts about ``ds``: views, frames, people, calibration ranges (world metres, degrees).

    Reads every calibration and annotation file, so a malformed one raises ``DatasetError`` here.
    """
    frames = ds.frames
    if not frames:
        from matrix_core.datasets.types import DatasetError

        raise DatasetError(f'{ds.root}: no frame has an image for every view')
    heights, dists, tilts = [], [], []
    x0, y0, x1, y1 = ds.area
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for frame in frames:
        for view in ds.views:
            cam = ds.camera(view, frame)
            heights.append(cam.center[2])
            dists.append(np.linalg.norm(cam.center[:2] - centre))
            tilts.append(cam.tilt_deg)
    people, per_frame, boxes = set(), [], 0
    for frame in ds.annotated_frames:
        persons = ds.annotations(frame)
        people.update(p.person_id for p in persons)
        per_frame.append(len(persons))
        boxes += sum(len(p.boxes) for p in persons)
    out = {
        'format': ds.format_name,
        'root': str(ds.root),
        'views': list(ds.views),
        'frames': len(frames),
        'frame_range': [frames[0], frames[-1]],
        'image_size': list(ds.image_size),
        'area_m': [round(v, 3) for v in ds.area],
        'annotated_frames': len(ds.annotated_frames),
        'people': len(people),
        'people_per_frame': [min(per_frame), max(per_frame)] if per_frame else [0, 0],
        'visible_boxes': boxes,
        'camera_height_m': _span(heights),
        'camera_distance_to_centre_m': _span(dists),
        'camera_tilt_below_horizon_deg': _span(tilts),
    }
    if hasattr(ds, 'trajectory_frames'):
        out['trajectory_frames'] = len(ds.trajectory_frames)
        out['has_reference'] = ds.has_reference
    return out


def format_summary(info: dict) -> str:
    """Aligned 'key: value' lines."""
    width = max(len(k) for k in info)
    return '\n'.join(f'{k.ljust(width)}  {v}' for k, v in info.items())
