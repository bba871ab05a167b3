"""One settings dataclass per component, exposed with the same names and defaults as CLI flags here
and as ROS parameters by ``matrix_ros.params`` (which reuses :func:`settings_fields`); launch files,
whose arguments are strings, use :func:`setting_to_string` and :func:`settings_from_strings`."""

import argparse
import dataclasses
import typing
from pathlib import Path

import yaml


@dataclasses.dataclass
class Settings:
    """The one base of the settings dataclasses that are put together (a node's: its wiring and its component's;
    fuse's: device, restarts, tracker). Each class validates its own fields in ``check``; ``__post_init__`` runs
    every class's ``check`` once, bases first, so that no class hands over to another (no ``super()`` chain)."""

    def __post_init__(self):
        for cls in reversed(type(self).__mro__):
            check = vars(cls).get('check')
            if check is not None:
                check(self)


def check_area(area, name: str = 'area') -> None:
    """The one check of a scene area setting: x_min y_min x_max y_max (metres), min < max."""
    if len(area) != 4 or area[0] >= area[2] or area[1] >= area[3]:
        raise ValueError(f'{name} must be x_min y_min x_max y_max, got {list(area)}')


def read_yaml(path) -> dict:
    """The mapping in a YAML config file ({} for an empty file); ValueError naming the file when it is not
    valid YAML or not a mapping, FileNotFoundError when it does not exist."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'config file not found: {path}')
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ValueError(f'{path}: not valid YAML: {exc}') from exc
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ValueError(f'{path}: expected a mapping of keys to values, got {type(data).__name__}')
    return data


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


def parse_bool(text: str) -> bool:
    """A true/false flag or parameter value: 1/0, true/false, yes/no, on/off (any case)."""
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
        group.add_argument(
            f'--{name}',
            type=parse_bool if typ is bool else typ,
            default=default,
            help=f'{help_text} (default: {default!r})',
            **extra,
        )


def settings_from_namespace(cls, namespace: argparse.Namespace):
    """Build ``cls`` from parsed flags; the dataclass's own ``__post_init__`` validates values. A dataclass with
    a ``site`` field takes the site's values where its flags were left at their MATRIX defaults
    (``matrix_core.site.parameter.follow_site``)."""
    from matrix_core.site.parameter import follow_site  # the site package reads its files with this module

    return follow_site(cls(**{name: getattr(namespace, name) for name, *_ in settings_fields(cls)}))


def setting_to_string(value) -> str:
    """A setting's value as a launch argument: true/false, numbers, lists comma separated."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, (list, tuple)):
        return ','.join(setting_to_string(v) for v in value)
    return str(value)


def _from_string(typ, text: str):
    return parse_bool(text) if typ is bool else typ(text)


def settings_from_strings(cls, values: dict):
    """Build ``cls`` from strings (launch arguments), missing names keeping their defaults. Lists are
    comma separated, optionally in brackets and quoted: ``D1,D2``, ``[D1, D2]``, ``['D1','D2']``, '' = []."""
    kwargs = {}
    for name, typ, _, _ in settings_fields(cls):
        if name not in values:
            continue
        text = str(values[name]).strip()
        if typing.get_origin(typ) in (list, tuple):
            inner = text[1:-1] if text.startswith('[') and text.endswith(']') else text
            items = [item.strip().strip('\'"') for item in inner.split(',')]
            kwargs[name] = [_from_string(typing.get_args(typ)[0], item) for item in items if item]
        else:
            try:
                kwargs[name] = _from_string(typ, text)
            except (ValueError, argparse.ArgumentTypeError) as exc:
                raise ValueError(f'{cls.__name__}.{name}: {exc}') from exc
    return cls(**kwargs)
