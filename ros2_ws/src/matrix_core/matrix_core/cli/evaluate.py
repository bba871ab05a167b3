"""``matrix-tracker evaluate --checkpoint CKPT DATASET``: detect and track with a trained BEV model on a
MATRIX folder, print one table of all metrics, write PNGs (heatmap vs ground truth, trajectories) and
the detections/tracks as text (``frame x y score`` / ``frame id x y``).

Image plane: each frame's tracks become boxes in every drone (``fusion.image_boxes``: the person cylinder
at the track's detection of the frame, projected with the camera the calibration source's homography implies
with the drone's reference intrinsics, as the live fuse node does), scored against the annotated boxes at
IoU >= ``--iou`` per drone and overall (``metrics.image_boxes``); written as ``boxes_2d.txt``
(``frame,id,x,y,w,h,score,drone``) and drawn for one frame in ``boxes_2d_FRAME.png``.

No frame ends the run: a view whose image or calibration cannot be used in a frame (unreadable, corrupt or
wrong-size image, missing or malformed calibration, NaN or singular homography or registration record) is
masked there; a frame whose ground truth, inputs or model step raises, or that the folder has only in part,
is not scored. Both are printed with their reasons and listed in ``metrics.json`` (``failures``: counts, then
each frame and view); the metrics are over the scored frames. A frame whose annotation file cannot be read
is left out of the image plane only (``failures.image_plane_failed_frames``); everything else is written.
``--out`` must be new or empty (``--overwrite``: write into it) and not be, contain or lie inside the dataset,
the calibration folder or the checkpoint.

``--site SITE``: the dataset's area and drones must be the site's and the checkpoint's cell the site's (an
error naming what differs, before any work); the BEV grid is then the site's area. Default: the site a site
dataset names, else MATRIX. The site's obstacles hide people from the image-plane boxes.

``--device`` (``auto`` | ``cpu`` | ``cuda`` | ``cuda:N``, ``matrix_core.device``): where the network runs; a GPU
this machine lacks is an error before anything is read.
"""

import dataclasses
import json
from pathlib import Path

import numpy as np

from matrix_core.cli.argument_types import add_site_argument, check_frame_range, fraction, non_negative_int
from matrix_core.device import DeviceSettings, resolve_device
from matrix_core.fusion.image_boxes import ImageBoxSettings
from matrix_core.fusion.settings import resolve_checkpoint
from matrix_core.output_paths import add_overwrite_argument, atomic_write_text, check_output
from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.tracking.settings import TrackerSettings


def add_parser(subparsers) -> None:
    from matrix_core.bev.calibration_sources import CALIBRATION_SOURCES

    p = subparsers.add_parser(
        'evaluate', help='metrics table + PNGs of a trained BEV model on a dataset', description=__doc__
    )
    p.add_argument('dataset', help='MATRIX-format folder or site dataset')
    p.add_argument(
        '--checkpoint',
        required=True,
        help='model checkpoint (.pt) written by train, or the name of '
        'one shipped in matrix_core/bev/checkpoints (e.g. detector_seed1.pt)',
    )
    p.add_argument(
        '--frames', type=non_negative_int, nargs=2, metavar=('FIRST', 'LAST'), help='frame range (inclusive)'
    )
    p.add_argument(
        '--calibration',
        default='ground_truth',
        choices=sorted(CALIBRATION_SOURCES),
        help='calibration source per frame (default: ground_truth)',
    )
    p.add_argument(
        '--calibration-dir',
        help='output folder of matrix-tracker calibrate (pnp) or register (registration) for those calibration sources',
    )
    p.add_argument('--drop-views', nargs='*', default=[], help='views to remove at test time, e.g. D2 D6')
    p.add_argument('--score-threshold', type=fraction, help='override the checkpoint\'s decoding threshold')
    p.add_argument('--out', default='out/evaluate', help='folder for PNGs, text files and metrics.json (new or empty)')
    add_overwrite_argument(p)
    p.add_argument('--heatmaps', type=non_negative_int, default=3, help='number of frames to draw heatmap PNGs for')
    p.add_argument('--iou', type=fraction, default=0.5, help='image-plane match threshold (default: 0.5)')
    add_site_argument(p, 'the dataset')
    add_settings_arguments(p, TrackerSettings)
    add_settings_arguments(p, ImageBoxSettings)
    add_settings_arguments(p, DeviceSettings)
    p.set_defaults(func=run)


def run(args) -> int:
    import torch

    from matrix_core.bev.checkpoint import load_model
    from matrix_core.bev.data import BevFrames
    from matrix_core.bev.evaluation import evaluate
    from matrix_core.bev.plots import save_heatmap_png, save_trajectories_png
    from matrix_core.metrics import write_bev_points
    from matrix_core.metrics.report import format_metrics

    device = resolve_device(settings_from_namespace(DeviceSettings, args).device)  # before any work
    checkpoint = resolve_checkpoint(args.checkpoint)
    out = check_output(args.out, [args.dataset, args.calibration_dir, checkpoint], args.overwrite)
    check_frame_range(args.frames)
    torch.set_num_threads(1)
    overrides = {} if args.score_threshold is None else {'score_threshold': args.score_threshold}
    from matrix_core.datasets import open_dataset
    from matrix_core.site.parameter import dataset_site

    site = dataset_site(args.site, open_dataset(args.dataset), f'--site {args.site}: {args.dataset}')
    model, settings = load_model(checkpoint, overrides)
    if args.site:  # the BEV grid over the site's area, in the checkpoint's cells (the fuse node's rule)
        from matrix_core.fusion.fuser import network_grid
        from matrix_core.fusion.settings import FuseSettings

        fuse = FuseSettings(area=list(site.area), cell_m=site.cell_m, checkpoint=str(checkpoint))
        network_grid(settings, fuse)  # ValueError naming both cells when the site's is not the checkpoint's
        settings = dataclasses.replace(settings, area=list(site.area))
    model = model.to(device)
    probe = BevFrames(
        args.dataset, settings, calibration=args.calibration, cache_images=False, calibration_dir=args.calibration_dir
    )
    unknown = set(args.drop_views) - set(probe.views)
    if unknown:
        raise ValueError(f'--drop-views: unknown views {sorted(unknown)}; views are {probe.views}')
    in_range = (lambda f: True) if not args.frames else (lambda f: args.frames[0] <= f <= args.frames[1])
    frames = [f for f in probe.frames if in_range(f)]
    if not frames:
        raise ValueError(f'no frames of {args.dataset} in {args.frames}')
    views = [v for v in probe.views if v not in args.drop_views]
    data = BevFrames(
        args.dataset,
        settings,
        frames,
        args.calibration,
        views,
        cache_images=False,
        calibration_dir=args.calibration_dir,
    )
    result = evaluate(model, data, settings_from_namespace(TrackerSettings, args))
    # frames the folder has files of but not every view's image and calibration: failed too, not dropped silently
    result.failed_frames.update(
        {f: f'dataset: {why}' for f, why in probe.dataset.incomplete_frames.items() if in_range(f)}
    )
    if not result.outputs:
        raise ValueError(f'no frame could be evaluated:\n{result.failures_text()}')
    print(format_metrics(result.detection, result.tracking, result.hota))
    if result.failures_text():
        print(result.failures_text())
    out.mkdir(parents=True, exist_ok=True)
    write_bev_points(out / 'detections.txt', result.detections)
    write_bev_points(out / 'tracks.txt', result.tracks)
    write_bev_points(out / 'ground_truth.txt', result.gt)
    image_plane, image_plane_failed = _image_plane(args, data, result, views, out, site)
    failures = result.failures_dict()
    failures['image_plane_frames_failed'] = len(image_plane_failed)
    failures['image_plane_failed_frames'] = [{'frame': f, 'reason': r} for f, r in sorted(image_plane_failed.items())]
    atomic_write_text(
        out / 'metrics.json',
        json.dumps(
            {
                'detection': result.detection.as_dict(),
                'tracking': result.tracking.as_dict(),
                'hota': result.hota.as_dict(),
                'image_plane': image_plane.as_dict() if image_plane else None,
                'site': site.name,
                'calibration': args.calibration,
                'views': views,
                'calibration_dir': args.calibration_dir,
                'failures': failures,
            },
            indent=2,
        ),
    )
    step = max(len(result.outputs) // max(args.heatmaps, 1), 1)
    for o in result.outputs[::step][: args.heatmaps]:
        gt = result.gt.xy[result.gt.frames == o.frame]
        save_heatmap_png(
            out / f'heatmap_{o.frame:04d}.png',
            o.heatmap,
            data.grid,
            gt,
            o.detections.xy,
            f'frame {o.frame}: heatmap, ground truth (o), detections (x)',
        )
    save_trajectories_png(
        out / 'trajectories.png',
        result.gt,
        result.tracks,
        data.grid,
        f'{Path(args.dataset).name}, frames {frames[0]}-{frames[-1]}'
        + (f' ({len(result.failed_frames)} failed)' if result.failed_frames else ''),
    )
    print(
        f'wrote {out}/: metrics.json, detections.txt, tracks.txt, boxes_2d.txt, trajectories.png, '
        f'heatmap_*.png, boxes_2d_*.png'
    )
    return 0


def _image_plane(args, data, result, views, out, site) -> tuple:
    """Score, print, write and draw the tracks' boxes in every drone (module docstring); returns the scores
    (None when nothing could be scored) and frame -> why it was left out of the image plane (its annotation
    file unreadable: that frame's boxes are not scored, the BEV metrics keep it)."""
    from matrix_core.evaluation.image_plane import draw_frame_png, homography_cameras, score_image_plane
    from matrix_core.metrics import BevPoints
    from matrix_core.metrics.image_boxes import format_view_table, write_mot_boxes
    from matrix_core.site.parameter import with_site

    failed = {}
    for f in result.scored_frames:
        try:
            data.dataset.annotations(f)
        except Exception as exc:  # one bad annotation file leaves its frame out of the image plane only
            failed[f] = f'annotations: {type(exc).__name__}: {exc}'
    scored = [f for f in result.scored_frames if f not in failed]
    for f, reason in sorted(failed.items()):
        print(f'image plane: frame {f} not scored: {reason}')
    if not scored:
        print('image plane: no frame with readable annotations; not scored')
        return None, failed
    tracks = result.track_detections
    keep = np.isin(tracks.frames, scored)
    tracks = BevPoints(
        tracks.frames[keep], tracks.xy[keep], None if tracks.ids is None else tracks.ids[keep], tracks.scores[keep]
    )
    camera_of = homography_cameras(data.dataset, data.homography_of)
    scores = score_image_plane(
        data.dataset,
        tracks,
        _or_none(camera_of),
        views,
        scored,
        with_site(settings_from_namespace(ImageBoxSettings, args), site),  # the site's obstacles
        args.iou,
    )
    print(f'image plane (2D boxes of the tracks in every drone, IoU >= {args.iou:g}):')
    print(format_view_table(scores.metrics))
    write_mot_boxes(out / 'boxes_2d.txt', scores.pred)
    frame = scored[len(scored) // 2]
    images = {v: image for v in views if (image := _or_none(data.dataset.load_image)(v, frame)) is not None}
    draw_frame_png(
        out / f'boxes_2d_{frame:04d}.png',
        images,
        scores.pred,
        scores.gt,
        frame,
        f'frame {frame}: tracks (id, colour) and annotated boxes (white)',
    )
    return scores, failed


def _or_none(fn):
    """``fn(view, frame)``, None where it raises: a view whose camera or image is broken in a frame has no
    boxes or tile there (``evaluate`` already masked and reported it)."""

    def call(view, frame):
        try:
            return fn(view, frame)
        except Exception:
            return None

    return call
