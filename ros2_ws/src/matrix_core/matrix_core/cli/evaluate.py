"""``matrix-tracker evaluate --checkpoint CKPT DATASET``: detect and track with a trained BEV model on a
MATRIX folder, print one table of all metrics, write PNGs (heatmap vs ground truth, trajectories) and
the detections/tracks as text (``frame x y score`` / ``frame id x y``).
"""

import json
from pathlib import Path

from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.tracking.settings import TrackerSettings


def add_parser(subparsers) -> None:
    from matrix_core.bev.calibration_sources import CALIBRATION_SOURCES

    p = subparsers.add_parser('evaluate', help='metrics table + PNGs of a trained BEV model on a dataset',
                              description=__doc__)
    p.add_argument('dataset', help='MATRIX-format folder')
    p.add_argument('--checkpoint', required=True, help='model checkpoint (.pt) written by train')
    p.add_argument('--frames', type=int, nargs=2, metavar=('FIRST', 'LAST'), help='frame range (inclusive)')
    p.add_argument('--calibration', default='ground_truth', choices=sorted(CALIBRATION_SOURCES),
                   help='calibration source per frame (default: ground_truth)')
    p.add_argument('--calibration-dir', help='output folder of matrix-tracker calibrate (pnp) or register '
                   '(registration) for those calibration sources')
    p.add_argument('--drop-views', nargs='*', default=[], help='views to remove at test time, e.g. D2 D6')
    p.add_argument('--score-threshold', type=float, help='override the checkpoint\'s decoding threshold')
    p.add_argument('--out', default='out/evaluate', help='folder for PNGs, text files and metrics.json')
    p.add_argument('--heatmaps', type=int, default=3, help='number of frames to draw heatmap PNGs for')
    add_settings_arguments(p, TrackerSettings)
    p.set_defaults(func=run)


def run(args) -> int:
    import torch

    from matrix_core.bev.checkpoint import load_model
    from matrix_core.bev.data import BevFrames
    from matrix_core.bev.evaluation import evaluate
    from matrix_core.bev.plots import save_heatmap_png, save_trajectories_png
    from matrix_core.metrics import write_bev_points
    from matrix_core.metrics.report import format_metrics

    torch.set_num_threads(1)
    overrides = {} if args.score_threshold is None else {'score_threshold': args.score_threshold}
    model, settings = load_model(args.checkpoint, overrides)
    probe = BevFrames(args.dataset, settings, calibration=args.calibration, cache_images=False,
                      calibration_dir=args.calibration_dir)
    unknown = set(args.drop_views) - set(probe.views)
    if unknown:
        raise ValueError(f'--drop-views: unknown views {sorted(unknown)}; views are {probe.views}')
    frames = probe.frames if not args.frames else [f for f in probe.frames if args.frames[0] <= f <= args.frames[1]]
    if not frames:
        raise ValueError(f'no frames of {args.dataset} in {args.frames}')
    views = [v for v in probe.views if v not in args.drop_views]
    data = BevFrames(args.dataset, settings, frames, args.calibration, views, cache_images=False,
                     calibration_dir=args.calibration_dir)
    result = evaluate(model, data, settings_from_namespace(TrackerSettings, args))
    print(format_metrics(result.detection, result.tracking))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_bev_points(out / 'detections.txt', result.detections)
    write_bev_points(out / 'tracks.txt', result.tracks)
    write_bev_points(out / 'ground_truth.txt', result.gt)
    (out / 'metrics.json').write_text(json.dumps({'detection': result.detection.as_dict(),
                                                  'tracking': result.tracking.as_dict(),
                                                  'calibration': args.calibration, 'views': views,
                                                  'calibration_dir': args.calibration_dir}, indent=2))
    step = max(len(result.outputs) // max(args.heatmaps, 1), 1)
    for o in result.outputs[::step][:args.heatmaps]:
        gt = result.gt.xy[result.gt.frames == o.frame]
        save_heatmap_png(out / f'heatmap_{o.frame:04d}.png', o.heatmap, data.grid, gt, o.detections.xy,
                         f'frame {o.frame}: heatmap, ground truth (o), detections (x)')
    save_trajectories_png(out / 'trajectories.png', result.gt, result.tracks, data.grid,
                          f'{Path(args.dataset).name}, frames {frames[0]}-{frames[-1]}')
    print(f'wrote {out}/: metrics.json, detections.txt, tracks.txt, trajectories.png, heatmap_*.png')
    return 0
