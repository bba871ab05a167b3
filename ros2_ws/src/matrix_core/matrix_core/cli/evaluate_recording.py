"""``matrix-tracker evaluate-recording REC --ground-truth SEQUENCE_BAG``: score what the live graph recorded.

REC is the ``recorder``'s bag folder (matrix_msgs/TrackArray tracks and detections, e.g. /tracks and
/detections of the ``fuse`` node; its /bev_heatmap too, if recorded, fixes the grid) or its MOT text
(``frame id x y``). SEQUENCE_BAG is the bag that was replayed (``/ground_truth/pedestrians``). Frames are
``round((stamp - start) / period)`` with the sequence clock stored in SEQUENCE_BAG (``--start-time`` and
``--frame-period`` override it; bags written before the clock was stored get 1.0 s and 0.5 s). Detection
metrics are of the detections when recorded (else of the tracks); tracking metrics and HOTA of the tracks. Prints the
table of ``evaluate`` and lists frames without tracks; ``--png`` draws the recorded tracks beside the
ground-truth trajectories.

Image plane, with ``--dataset`` (the MATRIX folder or site dataset the sequence bag was made from; bag frame ``i``
is its
``i``-th frame): the recorded ``/<drone>/detections_2d`` against the annotated boxes at IoU >= ``--iou``, per drone
and overall (precision, recall, MOTA, IDF1; ``metrics.image_boxes``), and the share of 2D ids that are
track ids of /tracks in the same frame; ``--boxes-2d`` writes them as ``frame,id,x,y,w,h,score,drone``,
``--png-2d`` draws one frame of every drone, ``--overlays DIR`` writes the recorded overlay images
(``/Dn/overlay/compressed``, when fuse published them) of that frame as ``DIR/overlay_Dn.png``.

``--site SITE``: the sequence bag's drones and ``--dataset``'s area and drones must be the site's (an error
naming what differs, before any work); the ground truth outside the site's area is ignored (``--area`` wins).

A bag without ``/ground_truth/pedestrians`` (a user's own recording) is not scored: the command says the
evaluation was skipped, writes nothing and exits 0.
"""

import json
from pathlib import Path

from matrix_core.cli.argument_types import (
    add_site_argument,
    check_frame_range,
    fraction,
    non_negative_float,
    non_negative_int,
    positive_float,
)
from matrix_core import topics
from matrix_core.output_paths import add_overwrite_argument, atomic_path, atomic_write_text, check_output


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'evaluate-recording', help='MODA/MOTA/IDF1... of a recorded live run vs a sequence bag', description=__doc__
    )
    p.add_argument('recording', help='recorder bag folder or MOT text file "frame id x y"')
    p.add_argument('--ground-truth', required=True, help='sequence bag with /ground_truth/pedestrians')
    tracks, detections = topics.graph_topic(topics.TRACKS), topics.graph_topic(topics.DETECTIONS)
    p.add_argument('--tracks-topic', default=tracks, help=f'TrackArray topic of the tracks (default: {tracks})')
    p.add_argument(
        '--detections-topic', default=detections, help=f'TrackArray topic of the detections (default: {detections})'
    )
    p.add_argument(
        '--start-time', type=non_negative_float, help='stamp of frame 0, seconds (default: the sequence bag\'s)'
    )
    p.add_argument('--frame-period', type=positive_float, help='seconds between frames (default: the sequence bag\'s)')
    p.add_argument(
        '--area',
        type=float,
        nargs=4,
        metavar=('X0', 'Y0', 'X1', 'Y1'),
        help='ground truth outside is ignored (default: the recorded heatmap grid, else none)',
    )
    p.add_argument(
        '--frames', type=non_negative_int, nargs=2, metavar=('FIRST', 'LAST'), help='frame range (inclusive)'
    )
    p.add_argument('--threshold', type=positive_float, default=0.5, help='detection match distance, m (default: 0.5)')
    p.add_argument('--gate', type=positive_float, default=1.0, help='tracking match distance, m (default: 1.0)')
    p.add_argument(
        '--dataset', help='MATRIX folder or site dataset of the sequence (annotated boxes): score detections_2d'
    )
    p.add_argument('--iou', type=fraction, default=0.5, help='image-plane match threshold (default: 0.5)')
    p.add_argument('--boxes-2d', help='with --dataset: write the recorded 2D boxes to this text file')
    p.add_argument('--png-2d', help='with --dataset: draw the middle frame of every drone into this PNG')
    p.add_argument('--overlays', help='with --dataset: write the recorded overlay images of that frame here')
    add_site_argument(p, 'the sequence bag and --dataset')
    p.add_argument('--json', help='also write the metrics to this JSON file')
    p.add_argument('--png', help='also draw the tracks and the ground-truth trajectories into this PNG')
    add_overwrite_argument(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from matrix_core.bags.clock import read_sequence_clock
    from matrix_core.evaluation.recording import ground_truth_from_bag, has_ground_truth, read_recording
    from matrix_core.evaluation.recording import score_recording
    from matrix_core.metrics.report import format_metrics

    _check_paths(args)
    if not has_ground_truth(args.ground_truth):  # a user's own recording: nothing to score against
        print(
            f'evaluation skipped: {args.ground_truth} has no ground truth ({topics.PEDESTRIANS_TOPIC}); nothing written'
        )
        return 0
    area = args.area
    if args.site:  # before any work: the sequence bag and --dataset are of the site; its area is scored
        area = area or list(_check_site(args).area)
    clock = read_sequence_clock(args.ground_truth).overridden(args.start_time, args.frame_period)
    recording = (
        read_recording(
            args.recording, tracks_topic=args.tracks_topic, detections_topic=args.detections_topic, clock=clock
        )
        if Path(args.recording).is_dir()
        else read_recording(args.recording)
    )
    gt = ground_truth_from_bag(args.ground_truth, clock)
    result = score_recording(recording, gt, area, args.frames, args.threshold, args.gate)
    gt_frames = sorted(set(result.gt.frames.tolist()))
    lost = sorted(set(gt_frames) - set(recording.track_frames)) if recording.track_frames is not None else None
    print(
        f'recording {args.recording}: detection metrics of the {result.detections_source}; '
        f'{len(gt_frames)} ground-truth frames'
        + (f', grid area {tuple(round(v, 3) for v in recording.area)}' if recording.area and area is None else '')
    )
    print(format_metrics(result.detection, result.tracking, result.hota))
    if lost is not None:
        print(f'frames without a TrackArray: {lost if lost else "none"}')
    if args.png:
        _draw(args.png, result, area or recording.area, args.recording)
    image_plane = _image_plane(args, clock, recording) if args.dataset else None
    if args.json:
        atomic_write_text(
            args.json,
            json.dumps(
                {
                    'detection': result.detection.as_dict(),
                    'tracking': result.tracking.as_dict() if result.tracking else None,
                    'hota': result.hota.as_dict() if result.hota else None,
                    'detections_source': result.detections_source,
                    'frames_without_tracks': lost,
                    'image_plane': image_plane,
                },
                indent=2,
            ),
        )
    return 0


def _check_paths(args) -> None:
    """Before any work: every output is new or empty (or ``--overwrite``) and none is, contains or lies inside
    an input; the inputs exist; the 2D outputs come with --dataset; the frame range is a range."""
    check_frame_range(args.frames)
    for flag, path in (
        ('recording', args.recording),
        ('--ground-truth', args.ground_truth),
        ('--dataset', args.dataset),
    ):
        if path is not None and not Path(path).exists():
            raise FileNotFoundError(f'{flag} {path}: no such file or folder')
    two_d = {'--boxes-2d': args.boxes_2d, '--png-2d': args.png_2d, '--overlays': args.overlays}
    if not args.dataset and any(two_d.values()):
        raise ValueError(f'{", ".join(f for f, v in two_d.items() if v)} need --dataset')
    inputs = [args.recording, args.ground_truth, args.dataset]
    outputs = {'--json': args.json, '--png': args.png, **two_d}
    for flag, path in outputs.items():
        if path:
            check_output(path, inputs, args.overwrite, flag)


def _check_site(args):
    """The site ``--site`` names; SiteError when the sequence bag has drones it lacks or ``--dataset`` is not
    of it (area, drones)."""
    from matrix_core.bags.reader import bag_topics
    from matrix_core.datasets.open import open_dataset
    from matrix_core.site.parameter import check_bag_drones, dataset_site, named_site

    site = named_site(args.site)
    check_bag_drones(site, bag_topics(args.ground_truth), f'--ground-truth {args.ground_truth}')
    if args.dataset:
        dataset_site(args.site, open_dataset(args.dataset), f'--site {args.site}: --dataset {args.dataset}')
    return site


def _image_plane(args, clock, recording) -> dict:
    """Score, print, write and draw the recorded 2D boxes (module docstring); their JSON form."""
    from matrix_core.datasets.open import open_dataset
    from matrix_core.evaluation.image_plane import annotated_boxes, draw_frame_png, ids_in_tracks, read_recorded_boxes
    from matrix_core.metrics.image_boxes import format_view_table, per_view_metrics, write_mot_boxes

    if not Path(args.recording).is_dir():
        raise ValueError('--dataset needs a recorder bag (the 2D boxes are not in MOT text)')
    dataset = open_dataset(args.dataset)
    pred = read_recorded_boxes(args.recording, clock)
    if args.frames:
        pred = pred.select((pred.frames >= args.frames[0]) & (pred.frames <= args.frames[1]))
    frames = [k for k in range(len(dataset.frames)) if not args.frames or args.frames[0] <= k <= args.frames[1]]
    gt = annotated_boxes(dataset, [dataset.frames[k] for k in frames], list(dataset.views), frames)
    metrics = per_view_metrics(gt, pred, args.iou)
    same_ids = ids_in_tracks(pred, recording.tracks) if recording.tracks is not None else float('nan')
    print(
        f'image plane: recorded detections_2d of {len(set(pred.views.tolist()))} drones vs the annotated boxes '
        f'of {args.dataset} (IoU >= {args.iou:g}); 2D ids that are /tracks ids of the frame: {100 * same_ids:.2f} %'
    )
    print(format_view_table(metrics))
    if args.boxes_2d:
        write_mot_boxes(args.boxes_2d, pred)
    if args.png_2d and frames:
        k = frames[len(frames) // 2]
        draw_frame_png(
            args.png_2d,
            {v: dataset.load_image(v, dataset.frames[k]) for v in dataset.views},
            pred,
            gt,
            k,
            f'live recording, frame {k}: detections_2d (id, colour) and annotated boxes (white)',
        )
        print(f'wrote {args.png_2d}')
    if args.overlays and frames:
        _write_overlays(args, clock, frames[len(frames) // 2])
    return {'per_drone': {v: m.as_dict() for v, m in metrics.items()}, 'ids_in_tracks': same_ids, 'iou': args.iou}


def _draw(path, result, area, name) -> None:
    """Tracks beside the ground truth over ``area`` (default: where the ground truth is, plus 1 m)."""
    import numpy as np

    from matrix_core.bev.plots import save_trajectories_png
    from matrix_core.geometry.grid import BevGrid
    from matrix_core.metrics import BevPoints

    if area is None:
        xy = result.gt.xy if len(result.gt) else np.zeros((1, 2))
        area = (*(xy.min(axis=0) - 1.0), *(xy.max(axis=0) + 1.0))
    tracks = result.recording.tracks
    if tracks is None:
        tracks = BevPoints(np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0, np.int64))
    save_trajectories_png(
        path, result.gt, tracks, BevGrid(*map(float, area)), f'live recording {Path(name).name}: tracks vs ground truth'
    )
    print(f'wrote {path}')


def _write_overlays(args, clock, frame: int) -> None:
    import cv2

    from matrix_core.evaluation.image_plane import read_recorded_overlays

    overlays = read_recorded_overlays(args.recording, clock, frame)
    Path(args.overlays).mkdir(parents=True, exist_ok=True)
    for view, image in overlays.items():
        with atomic_path(Path(args.overlays) / f'overlay_{view}.png') as tmp:
            cv2.imwrite(str(tmp), image)
    print(
        f'wrote {len(overlays)} overlay images of frame {frame} to {args.overlays}/'
        if overlays
        else f'no overlay images of frame {frame} in {args.recording} (fuse overlay off?)'
    )
