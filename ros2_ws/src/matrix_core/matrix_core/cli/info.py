"""``matrix-tracker info DATASET``: summarise a MATRIX, Wildtrack or MultiviewX folder."""

import json

from matrix_core.datasets import open_dataset
from matrix_core.datasets.summary import format_summary, summarize


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'info', help='summarise a dataset folder (drones, frames, people, calibration)', description=__doc__
    )
    p.add_argument('dataset', help='MATRIX, Wildtrack or MultiviewX folder')
    p.add_argument('--json', action='store_true', help='print JSON instead of aligned text')
    p.set_defaults(func=run)


def run(args) -> int:
    info = summarize(open_dataset(args.dataset))
    print(json.dumps(info, indent=2) if args.json else format_summary(info))
    return 0
