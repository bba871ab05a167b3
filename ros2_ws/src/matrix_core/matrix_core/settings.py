"""One settings dataclass per component, exposed with the same names and defaults as CLI flags here
and as ROS parameters by ``matrix_ros.params`` (which reuses :func:`settings_fields`)."""

import argparse
import dataclasses
import typing


def settings_fields(cls) -> list:
    """(name, type, default, help) of each field of a settings dataclass; help is ``metadata['help']``."""
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            raise TypeError(f'{cls.__name__}.{f.name} needs a default to be a setting')
        out.append((f.name, hints[f.name], default, f.metadata.get('help', '')))
    return out


def _parse_bool(text: str) -> bool:
    low = text.lower()
    if low in ('1', 'true', 'yes', 'on'):
        return True
    if low in ('0', 'false', 'no', 'off'):
        return False
    raise argparse.ArgumentTypeError(f'expected true/false, got {text!r}')


def add_settings_arguments(parser: argparse.ArgumentParser, cls) -> None:
    """Add one ``--name`` flag per field of ``cls`` (same name as the ROS parameter, underscores kept)."""
    group = parser.add_argument_group(f'{cls.__name__} (also ROS parameters of the same names)')
    for name, typ, default, help_text in settings_fields(cls):
        extra = {}
        if typing.get_origin(typ) in (list, tuple):
            typ, extra = typing.get_args(typ)[0], {'nargs': '*'}
        if typ not in (bool, int, float, str):
            raise TypeError(f'{cls.__name__}.{name}: unsupported setting type {typ}')
        if typ is bool and not extra:  # `--flag` alone means true; `--flag false` also works
            extra = {'nargs': '?', 'const': True}
        group.add_argument(f'--{name}', type=_parse_bool if typ is bool else typ, default=default,
                           help=f'{help_text} (default: {default!r})', **extra)


def settings_from_namespace(cls, namespace: argparse.Namespace):
    """Build ``cls`` from parsed flags; the dataclass's own ``__post_init__`` validates values."""
    return cls(**{name: getattr(namespace, name) for name, *_ in settings_fields(cls)})
