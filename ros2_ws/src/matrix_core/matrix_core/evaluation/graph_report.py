"""Per-view, per-frame scores of the calibration and registration the graph published, a summary table,
and an overview picture.

Convention: internal world metres and pixel-centre image pixels (``matrix_core.geometry.camera``);
``ground_H_img`` maps current-image pixels to world ground metres.
"""

import csv
from dataclasses import asdict, dataclass
from pathlib import Path

import cv2
import numpy as np

from matrix_core.calib.evaluation import pose_errors
from matrix_core.geometry.camera import Camera
from matrix_core.geometry.homography import apply_homography
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.ground_mask import visible_ground_grid
from matrix_core.register.registration import RegistrationStatus


@dataclass
class ViewFrameScore:
    """Scores of one view at one stamp; ``None`` where the graph published nothing for it."""

    view: str
    stamp: float
    rot_err_deg: float = None
    centre_err_m: float = None
    reg_status: RegistrationStatus = None
    reg_message: str = None
    reg_confidence: float = None
    reg_ground_err_m: float = None
    reg_ref_err_px: float = None  # in the reference image; None without the reference camera


def ground_homography_error_m(ground_H_img: np.ndarray, truth: Camera, area, step_m: float = 0.5) -> float:
    """Mean ground distance (metres) between where ``ground_H_img`` and the true camera put the pixels of
    a ``step_m`` grid of ground points of ``area`` visible in the true view."""
    world = visible_ground_grid(truth, area, step_m)
    if not len(world):
        raise ValueError('no ground point of the area is visible in this view')
    est = apply_homography(ground_H_img, truth.ground_to_img(world))
    return float(np.mean(np.linalg.norm(est - world, axis=1)))


def score_view_frame(
    view: str,
    stamp: float,
    truth: Camera,
    area,
    estimated: Camera = None,
    reg_status: RegistrationStatus = None,
    reg_confidence: float = None,
    ground_H_img=None,
    reg_message: str = None,
    ref_H_img=None,
    reference: Camera = None,
) -> ViewFrameScore:
    """Score what was published for ``view`` at ``stamp`` against the ``truth`` camera; with the registration's
    ``ref_H_img`` (3, 3) and the view's ``reference`` camera also the registration error in reference pixels
    (:func:`~matrix_core.register.evaluate.homography_error_px`, the ``register`` CLI's figure)."""
    score = ViewFrameScore(view, stamp, reg_status=reg_status, reg_message=reg_message, reg_confidence=reg_confidence)
    if estimated is not None:
        score.rot_err_deg, score.centre_err_m = pose_errors(estimated, truth)
    if reg_status == RegistrationStatus.OK and ground_H_img is not None:
        score.reg_ground_err_m = ground_homography_error_m(ground_H_img, truth, area)
        if ref_H_img is not None and reference is not None:
            score.reg_ref_err_px = homography_error_px(ref_H_img, truth, reference, area)
    return score


def _median(values) -> str:
    values = [v for v in values if v is not None]
    return f'{np.median(values):.3f}' if values else '-'


def summary_table(scores: list, views: list) -> str:
    """Plain-text table: one row per view and an 'all' row."""
    width = max([5, *(len(v) for v in views)])
    header = (
        f'{"view":>{width}} {"frames":>6} {"calib":>5} {"rot_deg":>8} {"centre_m":>8} '
        f'{"reg_ok":>6} {"conf":>6} {"ground_m":>8} {"ref_px":>7}'
    )
    lines = [header, '-' * len(header)]
    for name, rows in [(v, [s for s in scores if s.view == v]) for v in views] + [('all', scores)]:
        registered = sum(s.reg_status == RegistrationStatus.OK for s in rows)
        lines.append(
            f'{name:>{width}} {len(rows):>6} {sum(s.rot_err_deg is not None for s in rows):>5} '
            f'{_median([s.rot_err_deg for s in rows]):>8} {_median([s.centre_err_m for s in rows]):>8} '
            f'{registered:>6} {_median([s.reg_confidence for s in rows]):>6} '
            f'{_median([s.reg_ground_err_m for s in rows]):>8} {_median([s.reg_ref_err_px for s in rows]):>7}'
        )
    lines.append(
        'rot_deg, centre_m: median calibration error vs ground truth; ground_m: median mean ground '
        'error of the registration homography (image -> ground), metres; ref_px: median mean error of the '
        'registration (image -> reference image), reference pixels'
    )
    return '\n'.join(lines)


def _area_outline(area, n: int = 40) -> np.ndarray:
    x0, y0, x1, y1 = area
    t = np.linspace(0, 1, n)
    return np.concatenate(
        [
            np.column_stack([x0 + (x1 - x0) * t, np.full(n, y0)]),
            np.column_stack([np.full(n, x1), y0 + (y1 - y0) * t]),
            np.column_stack([x1 - (x1 - x0) * t, np.full(n, y1)]),
            np.column_stack([np.full(n, x0), y1 - (y1 - y0) * t]),
        ]
    )


def _draw_polyline(image, uv, colour, scale, thickness=2):
    ok = np.isfinite(uv).all(axis=1)
    pts = (uv[ok] * scale).round().astype(np.int32).reshape(-1, 1, 2)
    if len(pts) > 1:
        cv2.polylines(image, [pts], True, colour, thickness, cv2.LINE_AA)


def overview_image(
    images: dict, truth: dict, area, estimated: dict = None, ground_H_img: dict = None, thumb_width: int = 640
) -> np.ndarray:
    """Grid of thumbnails (BGR uint8), one per view, with the scene area's outline projected by the true
    calibration (white), the published calibration (green) and the registration homography (magenta).

    Args:
        images: view -> (H, W, 3) BGR image; truth / estimated: view -> Camera; ground_H_img: view -> (3, 3).
    """
    outline = _area_outline(area)
    tiles = []
    for view in sorted(images):
        img = images[view]
        scale = thumb_width / img.shape[1]
        tile = cv2.resize(img, (thumb_width, int(round(img.shape[0] * scale))), interpolation=cv2.INTER_AREA)
        _draw_polyline(tile, truth[view].ground_to_img(outline), (255, 255, 255), scale, 4)
        if estimated and view in estimated:
            _draw_polyline(tile, estimated[view].ground_to_img(outline), (0, 220, 0), scale, 2)
        if ground_H_img and view in ground_H_img:
            _draw_polyline(tile, apply_homography(np.linalg.inv(ground_H_img[view]), outline), (255, 0, 255), scale, 1)
        cv2.putText(tile, view, (10, 30), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (0, 255, 255), 2, cv2.LINE_AA)
        tiles.append(tile)
    if not tiles:
        raise ValueError('no image to draw')
    cols = min(4, len(tiles))
    while len(tiles) % cols:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.concatenate(tiles[i : i + cols], axis=1) for i in range(0, len(tiles), cols)]
    return np.concatenate(rows, axis=0)


def score_registration(
    view: str, stamp: float, truth: Camera, area, estimated: Camera = None, registration=None, reference=None
) -> ViewFrameScore:
    """:func:`score_view_frame` of a :class:`~matrix_core.register.registration.Registration` (or None), with
    the view's ``reference`` camera (or None)."""
    if registration is None:
        return score_view_frame(view, stamp, truth, area, estimated)
    return score_view_frame(
        view,
        stamp,
        truth,
        area,
        estimated,
        registration.status,
        registration.confidence,
        registration.ground_H_img if registration.ok else None,
        registration.message,
        registration.ref_H_img if registration.ok else None,
        reference,
    )


def true_references(references: dict, reference_stamps: dict, truth: dict, tolerance_s: float = 1e-4) -> tuple:
    """The camera each view's registration is scored against, and the views it is true for.

    A reference taken from a recorded frame (``site init``) has its calibration estimated from the boards;
    scoring against it would add that estimate's error to the registration's. Where the recording's ground
    truth has the reference frame (``truth`` at the view's ``reference_stamps`` stamp, within ``tolerance_s``),
    its true camera is used instead.

    Args:
        references: view -> reference Camera (the calibration register uses); reference_stamps: view -> stamp
            (seconds) of its reference frame; truth: (view, stamp) -> true Camera of the recording.

    Returns:
        (view -> Camera to score against, sorted views whose camera is the reference frame's true one).
    """
    cameras, true_views = dict(references), []
    for view, stamp in reference_stamps.items():
        if view not in cameras or stamp is None:
            continue
        near = [key for key in truth if key[0] == view and abs(key[1] - stamp) <= tolerance_s]
        if near:
            cameras[view] = truth[min(near, key=lambda key: abs(key[1] - stamp))]
            true_views.append(view)
    return cameras, sorted(true_views)


def write_graph_report(
    out_dir, views: list, area, truth: dict, estimated: dict, registrations: dict, images: dict, references=None
) -> int:
    """Score every (view, stamp) of ``truth`` and write ``graph_summary.txt`` (also printed),
    ``graph_scores.csv`` and ``graph_overview.png`` (the last stamp with images) to ``out_dir``.

    Args:
        truth, estimated: (view, stamp) -> Camera; registrations: (view, stamp) -> Registration;
        images: (view, stamp) -> (H, W, 3) BGR image; references: view -> reference Camera (the
        registration's pixel error is scored for the views it has).

    Returns:
        How many (view, stamp) pairs were scored.
    """
    scores = [
        score_registration(
            key[0], key[1], cam, area, estimated.get(key), registrations.get(key), (references or {}).get(key[0])
        )
        for key, cam in sorted(truth.items(), key=lambda kv: (kv[0][1], kv[0][0]))
    ]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    table = summary_table(scores, views)
    print(table, flush=True)
    (out / 'graph_summary.txt').write_text(table + '\n')
    if not scores:
        return 0
    with open(out / 'graph_scores.csv', 'w', newline='') as f:
        writer = csv.DictWriter(f, fieldnames=list(asdict(scores[0])))
        writer.writeheader()
        writer.writerows(asdict(sc) for sc in scores)
    last = max(k[1] for k in truth)
    keys = [(v, last) for v in views if (v, last) in images and (v, last) in truth]
    if keys:
        ok_h = {k[0]: registrations[k].ground_H_img for k in keys if k in registrations and registrations[k].ok}
        picture = overview_image(
            {k[0]: images[k] for k in keys},
            {k[0]: truth[k] for k in keys},
            area,
            {k[0]: estimated[k] for k in keys if k in estimated},
            ok_h,
        )
        cv2.imwrite(str(out / 'graph_overview.png'), picture)
        print(
            f'picture: {out / "graph_overview.png"} (white: true calibration, green: published '
            f'calibration, magenta: registration homography)',
            flush=True,
        )
    return len(scores)
