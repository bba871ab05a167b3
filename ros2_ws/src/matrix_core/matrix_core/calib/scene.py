"""The calibration scene loaded from YAML: boards, camera intrinsics, optional initial poses.

YAML layout (every position in the INTERNAL world frame: right-handed, metres, z up; for MATRIX data
internal y = -(file y)):

.. code-block:: yaml

    image_size: [1920, 1080]
    intrinsics:                      # internal pixel-centre convention (MATRIX file cx 960 -> 959.5)
      K: [fx, 0, cx, 0, fy, cy, 0, 0, 1]
      dist: [k1, k2, p1, p2, k3]     # optional, zeros by default
    boards:
      - {name: A, origin: [x, y, z], square: 0.25, inner_corners: [19, 19],
         axis_i: [1, 0, 0], axis_j: [0, -1, 0], first_cell_light: true}
    initial_poses:                   # optional prior of the first frame, per view (world -> camera)
      D1: {rvec: [..], tvec: [..]}

Instead of ``boards`` (and of ``image_size`` and ``intrinsics`` when all its drones share one camera), a scene
may name a site file (docs/site-file.md): ``site: matrix`` (a shipped site) or a path relative to the scene
file; the real MATRIX sample's scene is ``site: matrix``, so its boards are defined once, in the site file.

Unknown keys are rejected so that a typo never silently falls back to a default.
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from matrix_core.calib.board import Checkerboard
from matrix_core.geometry.camera import Camera, check_intrinsics
from matrix_core.locations import package_share
from matrix_core.settings import read_yaml

CONFIG_PACKAGE = 'matrix_calib'
DEFAULT_CONFIG_NAME = 'matrix_sample.yaml'
_TOP_KEYS = {'image_size', 'intrinsics', 'boards', 'initial_poses', 'site'}
_BOARD_KEYS = {'name', 'origin', 'square', 'inner_corners', 'axis_i', 'axis_j', 'first_cell_light'}


@dataclass
class CalibScene:
    """Boards, intrinsics (K (3, 3), dist (5,), image size) and initial priors (view -> :class:`Camera`)."""

    boards: list
    K: np.ndarray
    dist: np.ndarray
    image_size: tuple
    initial_poses: dict = field(default_factory=dict)

    def camera(self, cam_T_world: np.ndarray) -> Camera:
        """A :class:`Camera` with this scene's intrinsics at the given (4, 4) world -> camera pose."""
        return Camera(self.K, cam_T_world, int(self.image_size[0]), int(self.image_size[1]), self.dist)

    def with_intrinsics(self, K, dist, image_size) -> 'CalibScene':
        """A copy with other intrinsics (e.g. from a CameraInfo stream)."""
        return CalibScene(
            self.boards,
            np.asarray(K, float).reshape(3, 3),
            np.asarray(dist, float).reshape(5),
            tuple(int(v) for v in image_size),
            dict(self.initial_poses),
        )


def _check_keys(where: str, got: dict, allowed: set) -> None:
    unknown = set(got) - allowed
    if unknown:
        raise ValueError(f'{where}: unknown keys {sorted(unknown)} (allowed: {sorted(allowed)})')


def _site_scene(data: dict, where: str, folder: Path) -> tuple:
    """(boards, data with the site's camera as ``image_size`` / ``intrinsics`` where it gives none) of the site
    file ``data['site']`` names (a shipped site's name or a path relative to ``folder``)."""
    from matrix_core.site import load_site, site_path

    ref = str(data['site'])
    if 'boards' in data:
        raise ValueError(f'{where}: boards come from the site {ref}; give them in one place, not both')
    site = load_site(folder / ref if (folder / ref).is_file() else site_path(ref))
    if 'image_size' in data or 'intrinsics' in data:
        return list(site.boards), data
    cameras = {(d.camera.image_size, tuple(d.camera.K.ravel()), tuple(d.camera.dist)) for d in site.drones}
    if len(cameras) != 1:
        raise ValueError(f'{where}: the drones of site {ref} have different cameras: give image_size and intrinsics')
    size, K, dist = cameras.pop()
    return list(site.boards), {**data, 'image_size': list(size), 'intrinsics': {'K': list(K), 'dist': list(dist)}}


def _boards(data: dict, where: str) -> list:
    boards = []
    for k, b in enumerate(data['boards']):
        _check_keys(f'{where} boards[{k}]', b, _BOARD_KEYS)
        try:
            boards.append(
                Checkerboard(
                    name=str(b.get('name', f'board{k}')),
                    origin=tuple(float(v) for v in b['origin']),
                    square=float(b['square']),
                    inner_corners=tuple(int(v) for v in b['inner_corners']),
                    axis_i=tuple(float(v) for v in b.get('axis_i', (1, 0, 0))),
                    axis_j=tuple(float(v) for v in b.get('axis_j', (0, 1, 0))),
                    first_cell_light=bool(b.get('first_cell_light', True)),
                )
            )
        except KeyError as exc:
            raise ValueError(f'{where} boards[{k}]: missing {exc}') from None
    return boards


def scene_from_dict(data: dict, where: str = 'calibration config', folder=None) -> CalibScene:
    """Build a :class:`CalibScene` from the parsed YAML mapping (``folder``: where a relative ``site`` path is
    looked up, the current one by default); raises ValueError naming the problem."""
    if not isinstance(data, dict):
        raise ValueError(f'{where}: expected a mapping at the top level')
    _check_keys(where, data, _TOP_KEYS)
    if 'site' in data:
        boards, data = _site_scene(data, where, Path(folder or '.'))
    else:
        boards = _boards(data, where) if data.get('boards') else []
    if not boards:
        raise ValueError(f'{where}: no boards')
    intr = data.get('intrinsics') or {}
    _check_keys(f'{where} intrinsics', intr, {'K', 'dist'})
    if 'K' not in intr or 'image_size' not in data:
        raise ValueError(f'{where}: intrinsics.K and image_size are required')
    dist = np.zeros(5)
    d = np.asarray(intr.get('dist', []), dtype=np.float64).reshape(-1)
    dist[: min(5, len(d))] = d[:5]
    size = tuple(int(v) for v in data['image_size'])
    if len(size) != 2:
        raise ValueError(f'{where}: image_size must be [width, height], got {list(size)}')
    K = check_intrinsics(intr['K'], dist, size, f'{where} intrinsics')
    scene = CalibScene(boards, K, dist, size)
    for view, pose in (data.get('initial_poses') or {}).items():
        _check_keys(f'{where} initial_poses.{view}', pose, {'rvec', 'tvec'})
        cam = Camera.from_rvec_tvec(K, pose['rvec'], pose['tvec'], size[0], size[1], dist)
        scene.initial_poses[str(view)] = cam
    return scene


def default_config_path(name: str = DEFAULT_CONFIG_NAME) -> Path:
    """Path of a config shipped in ``matrix_calib/config`` (installed under ``share/matrix_calib/config``)."""
    return package_share(CONFIG_PACKAGE, 'config', name)


def config_for_dataset(root) -> Path:
    """The shipped config that fits a MATRIX-format folder: ``sim_<variant>.yaml`` for a folder written by
    this project's simulator (its ``matrix_tracker_meta.json`` names the variant; the configs are for
    1920x1080), else the real MATRIX sample's."""
    from matrix_core.datasets import MatrixDataset

    variant = MatrixDataset(root).meta.get('simulator', {}).get('config', {}).get('name')
    return default_config_path(f'sim_{variant}.yaml' if variant else DEFAULT_CONFIG_NAME)


def load_scene(path=None) -> CalibScene:
    """Load a scene YAML (``None`` or '' = the shipped MATRIX sample config)."""
    path = default_config_path() if not path else Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'calibration config not found: {path}')
    return scene_from_dict(read_yaml(path), str(path), path.parent)
