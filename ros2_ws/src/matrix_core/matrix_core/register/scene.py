"""Scene facts a dataset states about itself that the ground mask needs: obstacles and flat-ground extent.

Simulated folders carry ``matrix_tracker_meta.json`` with the simulator's scene config (internal world
metres): the central ``block`` (null in the simple variant), the ``pillars`` and the ``building_distance``
(the ground is flat up to the facades, on a square ring that far from the scene centre). The real MATRIX
sample has no such file and keeps the configured ``exclude_boxes`` / ``ground_margin_m``.
"""

from dataclasses import replace

from matrix_core.register.settings import RegisterSettings

# Keep this far inside the facades: a facade pixel's ray meets z = 0 behind the facade, never in front.
FACADE_CLEARANCE_M = 2.0


def _box(b: dict) -> list:
    (cx, cy), (sx, sy) = b['center'], b['size']
    return [cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2, float(b['height'])]


def scene_from_meta(meta: dict):
    """(exclude_boxes, ground_margin_m) stated by a dataset's meta dict, or None when it states none.

    exclude_boxes: flat list, groups ``x0 y0 x1 y1 height`` (block and pillars); ground_margin_m: how far
    the flat ground reaches beyond ``area`` on every side (up to ``FACADE_CLEARANCE_M`` short of the facades).
    """
    config = (meta or {}).get('simulator', {}).get('config')
    if not isinstance(config, dict) or 'area' not in config:
        return None
    boxes = [v for b in ([config.get('block')] + list(config.get('pillars') or [])) if b for v in _box(b)]
    x0, y0, x1, y1 = config['area']
    margin = 0.0
    if config.get('building_distance'):
        margin = max(0.0, config['building_distance'] - FACADE_CLEARANCE_M - max(x1 - x0, y1 - y0) / 2)
    return boxes, margin


def settings_for_dataset(settings: RegisterSettings, dataset) -> tuple:
    """(settings, note): ``settings`` with the dataset's own obstacles and ground extent when
    ``settings.scene_from_dataset`` and the dataset states them; note says what was taken ('' if nothing)."""
    scene = scene_from_meta(getattr(dataset, 'meta', None)) if settings.scene_from_dataset else None
    if scene is None:
        return settings, ''
    boxes, margin = scene
    note = (
        f'scene from {getattr(dataset, "root", "the dataset")}: {len(boxes) // 5} obstacle box(es), '
        f'flat ground {margin:.1f} m beyond the area'
    )
    return replace(settings, exclude_boxes=boxes, ground_margin_m=margin), note
