"""Seeded MATRIX-like scene simulator: textured square, central block, checkerboards, walking crowd,
eight moving drones with PID-aimed cameras, fast OpenCV rasteriser with a per-pixel person-id buffer, and
ground truth written in the MATRIX folder format (and rosbag2 through :mod:`matrix_core.bags`).

Everything here uses the internal convention of :mod:`matrix_core.geometry.camera` (right-handed world,
metres, z up, ground z = 0, pixel-centre image coordinates). The real MATRIX sample has its walkable square
at x in [0, 30], y in [-30, 0] in that convention; the simulator configs use the same placement so that
positionIDs written by :class:`~matrix_core.datasets.MatrixWriter` stay on the MATRIX 300 x 300 grid.
"""

from matrix_core.sim.config import SceneConfig, load_scene_config

__all__ = ['SceneConfig', 'load_scene_config']
