"""``matrix-tracker score GT.txt PRED.txt``: detection and tracking metrics of BEV points (metres).

GT lines: ``frame id x y``. PRED lines: ``frame id x y`` (tracks: detection, tracking and HOTA metrics) or
``frame x y [score]`` (detections: detection metrics only). World metres, integer frames.
"""

import json

from matrix_core.cli.argument_types import fraction, positive_float
from matrix_core.metrics import BevPoints, detection_metrics, hota_metrics, read_bev_points, tracking_metrics
from matrix_core.metrics.report import format_metrics


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'score', help='MODA/MODP/precision/recall, MOTA/MOTP/IDF1/MT/ML and HOTA of BEV text files', description=__doc__
    )
    p.add_argument('gt', help='ground truth, lines "frame id x y"')
    p.add_argument('pred', help='tracks "frame id x y" or detections "frame x y [score]"')
    p.add_argument(
        '--pred-format',
        choices=('auto', 'tracks', 'detections'),
        default='auto',
        help='how to read PRED; auto: 4 columns with an integer 2nd column are tracks (default: auto)',
    )
    p.add_argument('--min-score', type=fraction, default=0.0, help='ignore detections below this score (default: 0)')
    p.add_argument(
        '--threshold', type=positive_float, default=0.5, help='detection match distance in metres (default: 0.5)'
    )
    p.add_argument('--gate', type=positive_float, default=1.0, help='tracking match distance in metres (default: 1.0)')
    p.add_argument('--json', action='store_true', help='print JSON instead of a table')
    p.set_defaults(func=run)


def run(args) -> int:
    gt = read_bev_points(args.gt, with_ids=True)
    with_ids = {'auto': None, 'tracks': True, 'detections': False}[args.pred_format]
    pred = read_bev_points(args.pred, with_ids=with_ids)
    if not pred.has_ids and args.min_score > 0:
        keep = pred.scores >= args.min_score
        pred = BevPoints(pred.frames[keep], pred.xy[keep], scores=pred.scores[keep])
    det = detection_metrics(gt, pred, args.threshold)
    trk = tracking_metrics(gt, pred, args.gate) if pred.has_ids else None
    hota = hota_metrics(gt, pred, args.gate) if pred.has_ids else None
    if args.json:
        print(
            json.dumps(
                {
                    'detection': det.as_dict(),
                    'tracking': trk.as_dict() if trk else None,
                    'hota': hota.as_dict() if hota else None,
                },
                indent=2,
            )
        )
    else:
        print(format_metrics(det, trk, hota))
    return 0
