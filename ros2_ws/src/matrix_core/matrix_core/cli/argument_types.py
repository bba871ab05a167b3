"""argparse types for numbers with a range: a value out of range is a usage error naming the flag (exit 2,
no traceback), checked before any work, and no negative count reaches a Python slice."""

import argparse
import math


def _number(kind, text: str, what: str):
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not {what}') from None
    if isinstance(value, float) and not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'{text!r} is not {what}')
    return value


def non_negative_int(text: str) -> int:
    """An integer >= 0 (a count where 0 means "all" or "none")."""
    value = _number(int, text, 'an integer >= 0')
    if value < 0:
        raise argparse.ArgumentTypeError(f'{value} is negative; give an integer >= 0')
    return value


def positive_int(text: str) -> int:
    """An integer >= 1."""
    value = _number(int, text, 'an integer >= 1')
    if value < 1:
        raise argparse.ArgumentTypeError(f'{value} is not an integer >= 1')
    return value


def positive_float(text: str) -> float:
    """A finite number > 0 (a period, a distance)."""
    value = _number(float, text, 'a finite number > 0')
    if value <= 0:
        raise argparse.ArgumentTypeError(f'{value:g} is not > 0')
    return value


def non_negative_float(text: str) -> float:
    """A finite number >= 0."""
    value = _number(float, text, 'a finite number >= 0')
    if value < 0:
        raise argparse.ArgumentTypeError(f'{value:g} is negative')
    return value


def fraction(text: str) -> float:
    """A number in [0, 1] (an IoU, a score threshold)."""
    value = _number(float, text, 'a number in [0, 1]')
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f'{value:g} is not in [0, 1]')
    return value


def check_frame_range(frames, flag: str = '--frames') -> None:
    """``FIRST LAST`` of a frame range: both >= 0 and FIRST <= LAST, else a ValueError naming the flag."""
    if frames is not None and (frames[0] < 0 or frames[1] < frames[0]):
        raise ValueError(f'{flag} {frames[0]} {frames[1]}: needs 0 <= FIRST <= LAST')


def add_site_argument(parser, data: str) -> None:
    """``--site SITE`` of a command that reads ``data`` (``matrix_core.site.parameter.dataset_site``)."""
    from matrix_core.site.shipped import shipped_sites

    parser.add_argument(
        '--site',
        help=f'site file or shipped site ({", ".join(shipped_sites())}) of {data}; default: the site a site dataset '
        f'names, else MATRIX; given, {data} must agree with it (area, drones), else an error before any work',
    )
