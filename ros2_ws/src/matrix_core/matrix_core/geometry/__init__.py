"""Camera and ground-plane geometry in the project's single convention (see ``camera.py``)."""

from matrix_core.geometry.camera import Camera
from matrix_core.geometry.grid import BevGrid
from matrix_core.geometry.homography import apply_homography, ground_homography

__all__ = ['Camera', 'BevGrid', 'apply_homography', 'ground_homography']
