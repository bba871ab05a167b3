"""Entry point of ``matrix-tracker``: one subcommand per module listed in ``SUBCOMMANDS``.

Each subcommand module has ``add_parser(subparsers)``, which registers its parser and sets ``func``.
"""

import argparse
import importlib
import sys

from matrix_core.datasets.types import DatasetError

SUBCOMMANDS = (
    'info',
    'bag',
    'track',
    'score',
    'register',
    'train',
    'evaluate',
    'calibrate',
    'simulate',
    'evaluate-recording',
    'experiments',
    'site',
)


class _Parser(argparse.ArgumentParser):
    """argparse that names the closest flag of the subcommand for each flag it does not know."""

    def error(self, message):
        if message.startswith('unrecognized arguments:'):
            import difflib

            flags = [o for a in self._subcommand_actions() for o in a.option_strings if o.startswith('--')]
            for word in message.split(':', 1)[1].split():
                close = difflib.get_close_matches(word.split('=')[0], flags, 1) if word.startswith('-') else []
                if close:
                    message += f'; {word}: did you mean {close[0]}?'
            message += ' (--help lists them)'
        super().error(message)

    def _subcommand_actions(self):
        """The actions of the subcommand being parsed (this parser's own when it has none)."""
        argv = sys.argv[1:] if self._argv is None else self._argv
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for word in argv:
                    if word in action.choices:
                        return action.choices[word]._actions
        return self._actions

    _argv = None

    def parse_args(self, args=None, namespace=None):
        self._argv = None if args is None else list(args)
        return super().parse_args(args, namespace)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog='matrix-tracker', description='Multi-drone multi-view pedestrian detection and tracking: offline tools.'
    )
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', required=True)
    for name in SUBCOMMANDS:
        importlib.import_module(f'matrix_core.cli.{name.replace("-", "_")}').add_parser(sub)
    return parser


def main(argv=None) -> int:
    """Run one subcommand; its exit code. Bad input (a usage error, a missing or malformed file, an output
    that would overwrite an input) is one line on stderr and code 2, never a traceback."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse printed the usage error (or --help): its code, also when called in-process
        return exc.code if isinstance(exc.code, int) else 2
    try:
        return int(args.func(args) or 0)
    except (DatasetError, FileNotFoundError, FileExistsError, NotADirectoryError, ValueError) as exc:
        print(f'matrix-tracker {args.command}: error: {exc}', file=sys.stderr)
        return 2
    except OSError as exc:  # unreadable input or unwritable output (permissions, disk full): named, no traceback
        print(f'matrix-tracker {args.command}: error: {exc}', file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
