"""Entry point of ``matrix-tracker``: one subcommand per module listed in ``SUBCOMMANDS``.

Each subcommand module has ``add_parser(subparsers)``, which registers its parser and sets ``func``.
"""

import argparse
import importlib
import sys

from matrix_core.datasets.types import DatasetError

SUBCOMMANDS = ('info', 'bag', 'track', 'score', 'register', 'train', 'evaluate', 'calibrate', 'simulate',
               'evaluate-recording', 'experiments')


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog='matrix-tracker',
        description='Multi-drone multi-view pedestrian detection and tracking: offline tools.')
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', required=True)
    for name in SUBCOMMANDS:
        importlib.import_module(f'matrix_core.cli.{name.replace("-", "_")}').add_parser(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (DatasetError, FileNotFoundError, FileExistsError, ValueError) as exc:
        print(f'matrix-tracker {args.command}: error: {exc}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
