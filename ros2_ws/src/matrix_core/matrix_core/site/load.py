"""Strict loader of site files: YAML -> :class:`~matrix_core.site.schema.Site`, or a :class:`SiteError` naming the
file, the key and the fault before anything starts.

Checked here (the file alone, no other file read): unknown keys (named with the allowed ones), missing keys,
types and ranges, 1 to 16 drones with distinct names usable as topic namespaces, intrinsics, boards inside the
area, obstacle sizes, and that the ``references.source`` and the drones' ``reference`` entries agree. Whether
the reference files exist is checked by :func:`matrix_core.site.references.require_references`, for the
commands that read them (a site whose references are to be simulated loads without them).
"""

import math
import os
import re
from pathlib import Path

import numpy as np

from matrix_core.calib.board import Checkerboard
from matrix_core.geometry.camera import check_intrinsics
from matrix_core.settings import read_yaml
from matrix_core.site.schema import (
    CalibrationFormat,
    CalibrationRef,
    CameraSpec,
    DroneSpec,
    ObstacleSpec,
    ReferenceSource,
    ReferenceSpec,
    Site,
)

FORMAT_VERSION = 1
MAX_DRONES = 16
# A drone's name is its topic namespace (``<name>/image_raw``): one ROS name token.
_DRONE_NAME = re.compile(r'^[A-Za-z][A-Za-z0-9_]*$')
_VARIABLE = re.compile(r'\$\{([A-Za-z_][A-Za-z0-9_]*)\}')

_TOP = {
    'version': True,
    'name': True,
    'area': True,
    'cell_m': True,
    'references': True,
    'drones': True,
    'boards': False,
    'obstacles': False,
}
_REFERENCES = {'source': True, 'root': False}
_DRONE = {'name': True, 'camera': True, 'reference': False, 'altitude_m': False, 'home': False}
_CAMERA = {'image_size': True, 'K': True, 'dist': False}
_REFERENCE = {'image': True, 'calibration': True, 'stamp_s': False}
_CALIBRATION = {'format': True, 'intrinsic': True, 'extrinsic': True}
_BOARD = {
    'name': True,
    'origin': True,
    'square': True,
    'inner_corners': True,
    'axis_i': False,
    'axis_j': False,
    'first_cell_light': False,
}
_OBSTACLE = {'name': True, 'footprint': True, 'height': True}


class SiteError(ValueError):
    """A site file that cannot be used; the message names the file, the key and the fault."""


class _Where:
    """The file and key path an error names (``plaza.yaml: drones[2] (P3).camera.K: ...``)."""

    def __init__(self, path, key: str = ''):
        self.path, self.key = path, key

    def __truediv__(self, key) -> '_Where':
        if isinstance(key, int):
            return _Where(self.path, f'{self.key}[{key}]')
        return _Where(self.path, f'{self.key}.{key}' if self.key else str(key))

    def named(self, name) -> '_Where':
        return _Where(self.path, f'{self.key} ({name})')

    def error(self, problem: str) -> SiteError:
        return SiteError(f'{self.path}: {self.key}: {problem}' if self.key else f'{self.path}: {problem}')


def _mapping(where: _Where, value, keys: dict) -> dict:
    """``value`` as a mapping with only the allowed ``keys`` (name -> required) and every required one."""
    if not isinstance(value, dict):
        raise where.error(f'expected a mapping with keys {sorted(keys)}, got {_kind(value)}')
    unknown = sorted(str(k) for k in value if k not in keys)
    if unknown:
        which = 'key' if len(unknown) == 1 else 'keys'
        raise where.error(f'unknown {which} {", ".join(map(repr, unknown))} (allowed: {", ".join(sorted(keys))})')
    missing = [k for k, required in keys.items() if required and k not in value]
    if missing:
        raise where.error(f'missing {", ".join(map(repr, missing))}')
    return value


def _kind(value) -> str:
    return 'nothing' if value is None else f'{type(value).__name__} {value!r}'


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(where: _Where, value, positive: bool = False) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise where.error(f'expected a number, got {_kind(value)}')
    if positive and not value > 0:
        raise where.error(f'must be positive, got {value}')
    return float(value)


def _numbers(where: _Where, value, n: int) -> tuple:
    """A list of exactly ``n`` finite numbers."""
    if not isinstance(value, list) or len(value) != n or not all(_is_number(v) and math.isfinite(v) for v in value):
        raise where.error(f'expected a list of {n} numbers, got {_kind(value)}')
    return tuple(float(v) for v in value)


def _text(where: _Where, value) -> str:
    if not isinstance(value, str) or not value.strip():
        raise where.error(f'expected a non-empty string, got {_kind(value)}')
    return value


def _choice(where: _Where, value, enum_cls):
    allowed = [e.value for e in enum_cls]
    if value not in allowed:
        raise where.error(f'expected one of {", ".join(allowed)}, got {_kind(value)}')
    return enum_cls(value)


def _rectangle(where: _Where, value) -> tuple:
    """(x_min, y_min, x_max, y_max) with x_min < x_max and y_min < y_max."""
    x0, y0, x1, y1 = _numbers(where, value, 4)
    if not (x0 < x1 and y0 < y1):
        raise where.error(f'expected [x_min, y_min, x_max, y_max] with x_min < x_max and y_min < y_max, got {value}')
    return (x0, y0, x1, y1)


def expand_variables(text: str):
    """(expanded text, None) or (None, the name of the first ``${NAME}`` that is not set in the environment)."""
    for name in _VARIABLE.findall(text):
        if name not in os.environ:
            return None, name
    return _VARIABLE.sub(lambda m: os.environ[m.group(1)], text), None


def _camera(where: _Where, value) -> CameraSpec:
    data = _mapping(where, value, _CAMERA)
    size = data['image_size']
    if not (
        isinstance(size, list) and len(size) == 2 and all(isinstance(v, int) and not isinstance(v, bool) for v in size)
    ):
        raise (where / 'image_size').error(f'expected [width, height] in whole pixels, got {_kind(size)}')
    if min(size) <= 0:
        raise (where / 'image_size').error(f'must be positive, got {size}')
    K = np.array(_numbers(where / 'K', data['K'], 9)).reshape(3, 3)
    dist = np.zeros(5)
    if 'dist' in data:
        d = data['dist']
        if not isinstance(d, list) or not 1 <= len(d) <= 5:
            raise (where / 'dist').error(f'expected 1 to 5 numbers (k1, k2, p1, p2, k3), got {_kind(d)}')
        dist[: len(d)] = _numbers(where / 'dist', d, len(d))
    try:
        K = check_intrinsics(K, dist, size, 'camera')
    except ValueError as exc:
        raise where.error(str(exc).removeprefix('camera: ')) from None
    if not (K[0, 0] > 0 and K[1, 1] > 0 and np.allclose(K[2], [0.0, 0.0, 1.0])):
        raise (where / 'K').error(f'expected [fx, 0, cx, 0, fy, cy, 0, 0, 1] with fx, fy > 0, got {data["K"]}')
    return CameraSpec((int(size[0]), int(size[1])), K, dist)


def _reference(where: _Where, value) -> ReferenceSpec:
    data = _mapping(where, value, _REFERENCE)
    cal = _mapping(where / 'calibration', data['calibration'], _CALIBRATION)
    fmt = _choice(where / 'calibration' / 'format', cal['format'], CalibrationFormat)
    calibration = CalibrationRef(
        fmt,
        Path(_text(where / 'calibration' / 'intrinsic', cal['intrinsic'])),
        Path(_text(where / 'calibration' / 'extrinsic', cal['extrinsic'])),
    )
    stamp = _number(where / 'stamp_s', data['stamp_s']) if 'stamp_s' in data else None
    return ReferenceSpec(Path(_text(where / 'image', data['image'])), calibration, stamp)


def _drone(where: _Where, value, source: ReferenceSource) -> DroneSpec:
    data = _mapping(where, value, _DRONE)
    name = data['name']
    if not isinstance(name, str) or not _DRONE_NAME.match(name):
        raise (where / 'name').error(
            f'expected a name of letters, digits and _ starting with a letter (it is the topic namespace), '
            f'got {_kind(name)}'
        )
    where = where.named(name)
    altitude = _number(where / 'altitude_m', data['altitude_m'], positive=True) if 'altitude_m' in data else None
    home = _numbers(where / 'home', data['home'], 2) if 'home' in data else None
    reference = None
    if source is ReferenceSource.FILES:
        if 'reference' not in data:
            raise where.error(
                'no reference (references.source is files: every drone names its reference image and calibration; '
                'a site whose references the simulator is to make says source: simulate)'
            )
        reference = _reference(where / 'reference', data['reference'])
    elif 'reference' in data:
        raise (where / 'reference').error('given, but references.source is simulate (the simulator is to make it)')
    return DroneSpec(name, _camera(where / 'camera', data['camera']), reference, altitude, home)


def _board(where: _Where, value, area: tuple) -> Checkerboard:
    data = _mapping(where, value, _BOARD)
    name = _text(where / 'name', data['name'])
    where = where.named(name)
    corners = data['inner_corners']
    if not (
        isinstance(corners, list)
        and len(corners) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) for v in corners)
    ):
        raise (where / 'inner_corners').error(f'expected [nx, ny] whole numbers, got {_kind(corners)}')
    light = data.get('first_cell_light', True)
    if not isinstance(light, bool):
        raise (where / 'first_cell_light').error(f'expected true or false, got {_kind(light)}')
    try:
        board = Checkerboard(
            name=name,
            origin=_numbers(where / 'origin', data['origin'], 3),
            square=_number(where / 'square', data['square'], positive=True),
            inner_corners=tuple(corners),
            axis_i=_numbers(where / 'axis_i', data.get('axis_i', [1.0, 0.0, 0.0]), 3),
            axis_j=_numbers(where / 'axis_j', data.get('axis_j', [0.0, 1.0, 0.0]), 3),
            first_cell_light=light,
        )
    except ValueError as exc:
        raise where.error(str(exc).removeprefix(f'board {name}: ')) from None
    # The board's outer edge: one square beyond the outermost inner corners on every side.
    edge = board.points([-1, board.nx, -1, board.nx], [-1, -1, board.ny, board.ny])
    x0, y0, x1, y1 = area
    tol = 1e-9
    if not (
        np.all(edge[:, 0] >= x0 - tol)
        and np.all(edge[:, 0] <= x1 + tol)
        and np.all(edge[:, 1] >= y0 - tol)
        and np.all(edge[:, 1] <= y1 + tol)
    ):
        lo, hi = edge[:, :2].min(axis=0), edge[:, :2].max(axis=0)
        raise where.error(
            f'lies outside the area {list(area)}: it spans x {lo[0]:g}..{hi[0]:g}, y {lo[1]:g}..{hi[1]:g} m'
        )
    return board


def _obstacle(where: _Where, value) -> ObstacleSpec:
    data = _mapping(where, value, _OBSTACLE)
    name = _text(where / 'name', data['name'])
    where = where.named(name)
    return ObstacleSpec(
        name, _rectangle(where / 'footprint', data['footprint']), _number(where / 'height', data['height'], True)
    )


def _list(where: _Where, value, required: bool) -> list:
    if value is None and not required:
        return []
    if not isinstance(value, list):
        raise where.error(f'expected a list, got {_kind(value)}')
    return value


def _distinct(where: _Where, names: list, what: str) -> None:
    seen = {}
    for i, name in enumerate(names):
        if not isinstance(name, str):  # a wrong type is reported with the entry's own checks
            continue
        if name in seen:
            raise where.error(f'duplicate {what} name {name!r} (entries {seen[name]} and {i})')
        seen[name] = i


def site_from_dict(data, path) -> Site:
    """Build a :class:`Site` from the parsed YAML of the site file at ``path`` (relative paths in it are
    relative to the file's folder); :class:`SiteError` naming the key and the fault."""
    path = Path(path).resolve()
    top = _Where(path)
    data = _mapping(top, data, _TOP)
    version = data['version']
    if version != FORMAT_VERSION:
        raise (top / 'version').error(
            f'this matrix-tracker reads site files of version {FORMAT_VERSION}, got {version!r}'
        )
    area = _rectangle(top / 'area', data['area'])
    cell_m = _number(top / 'cell_m', data['cell_m'], positive=True)
    refs = _mapping(top / 'references', data['references'], _REFERENCES)
    source = _choice(top / 'references' / 'source', refs['source'], ReferenceSource)
    root_text = _text(top / 'references' / 'root', refs.get('root', '.'))
    if '$' in _VARIABLE.sub('', root_text):
        raise (top / 'references' / 'root').error(f'a variable is written ${{NAME}}, got {root_text!r}')
    expanded, _ = expand_variables(root_text)
    root = None if expanded is None else (path.parent / expanded).resolve()

    drones_data = _list(top / 'drones', data['drones'], required=True)
    if not 1 <= len(drones_data) <= MAX_DRONES:
        raise (top / 'drones').error(f'a site has 1 to {MAX_DRONES} drones, got {len(drones_data)}')
    if all(isinstance(d, dict) for d in drones_data):  # names first: a duplicate is named before its details
        _distinct(top / 'drones', [d.get('name') for d in drones_data], 'drone')
    drones = tuple(_drone(top / 'drones' / i, d, source) for i, d in enumerate(drones_data))

    boards_data = _list(top / 'boards', data.get('boards'), required=False)
    boards = tuple(_board(top / 'boards' / i, b, area) for i, b in enumerate(boards_data))
    _distinct(top / 'boards', [b.name for b in boards], 'board')
    obstacles_data = _list(top / 'obstacles', data.get('obstacles'), required=False)
    obstacles = tuple(_obstacle(top / 'obstacles' / i, o) for i, o in enumerate(obstacles_data))
    _distinct(top / 'obstacles', [o.name for o in obstacles], 'obstacle')
    return Site(
        path=path,
        name=_text(top / 'name', data['name']),
        area=area,
        cell_m=cell_m,
        drones=drones,
        boards=boards,
        obstacles=obstacles,
        references=source,
        references_root=root,
        references_root_text=root_text,
    )


def load_site(path, require_references: bool = False) -> Site:
    """Load and validate the site file at ``path``.

    Args:
        path: the YAML file.
        require_references: also check that every drone's reference image and calibration can be read
            (:func:`matrix_core.site.references.require_references`), for commands that use them.

    Raises:
        SiteError: naming the file, the key and the fault (FileNotFoundError when there is no such file).
    """
    path = Path(path)
    try:
        data = read_yaml(path)
    except ValueError as exc:
        raise SiteError(str(exc)) from None
    site = site_from_dict(data, path)
    if require_references:
        from matrix_core.site.references import require_references as check

        check(site)
    return site
