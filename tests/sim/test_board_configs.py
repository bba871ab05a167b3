"""The boards of each simulator variant (``sim/configs/<variant>.yaml``) are written a second time, in the
calibration convention, in ``matrix_calib/config/sim_<variant>.yaml``: both must describe the same inner
corners and the same light/dark squares, so that moving a board in one file and not the other fails here."""

import numpy as np
import pytest

from matrix_core.calib.scene import default_config_path, load_scene
from matrix_core.sim.config import VARIANTS, load_scene_config
from matrix_core.sim.scene import board_corners


def _sim_is_dark(boards, xy: np.ndarray) -> np.ndarray:
    """(N,) bool: the simulator paints the square containing each (N, 2) point black (square (i, j) of a
    board, counted from its (x_min, y_min) corner, is black when i + j is even)."""
    dark = np.zeros(len(xy), bool)
    for b in boards:
        ij = np.floor((xy - np.asarray(b.origin)) / b.square_m + 1e-9).astype(int)
        on = np.all((ij >= 0) & (ij < b.squares), axis=1)
        dark |= on & (ij.sum(axis=1) % 2 == 0)
    return dark


@pytest.mark.parametrize('variant', VARIANTS)
def test_calibration_boards_match_the_simulator(variant):
    sim = load_scene_config(variant).boards
    calib = load_scene(default_config_path(f'sim_{variant}.yaml')).boards
    sim_corners = np.concatenate([board_corners(b, k)[1] for k, b in enumerate(sim)])
    calib_corners = np.concatenate([b.corners_world() for b in calib])
    key = lambda pts: sorted(map(tuple, np.round(pts, 6)))  # noqa: E731
    assert key(sim_corners) == key(calib_corners)
    for board in calib:  # every square of the board, by its centre
        a, b = np.meshgrid(np.arange(board.nx + 1), np.arange(board.ny + 1))
        centres = board.points(a.ravel() - 0.5, b.ravel() - 0.5)
        light = board.cell_sign(a.ravel(), b.ravel()) > 0
        np.testing.assert_array_equal(light, ~_sim_is_dark(sim, centres[:, :2]), err_msg=board.name)
