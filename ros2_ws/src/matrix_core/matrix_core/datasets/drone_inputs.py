"""What a drone of the live graph reads from the dataset folder at start-up, checked before anything starts.

Every drone's ``register`` reads its reference image and calibration, its ``calib`` takes its first prior
from that calibration, and ``fuse`` the reference intrinsics (``fusion.image_outputs.ViewCameras``). A drone
whose files cannot be read would end its own process and fuse's at start; :func:`unreadable_drones` names it
and why, so that the graph can leave it out and run the others.
"""

from matrix_core.datasets.types import DatasetError


def unreadable_drones(dataset, views) -> dict:
    """view -> why its start-up inputs cannot be used, for each of ``views`` whose reference image (decoded
    and checked whole: ``datasets.base.read_image``) or reference calibration cannot be read from ``dataset``
    (a :class:`~matrix_core.datasets.MatrixDataset`); the others are not in it."""
    problems = {}
    for view in views:
        try:
            dataset.reference_image(view)
            dataset.reference_camera(view)
        except (DatasetError, OSError, ValueError) as exc:
            problems[view] = f'reference: {exc}'
    return problems


def left_out_text(left_out: dict) -> str:
    """One line naming each drone left out (view -> why, as :func:`unreadable_drones` gives) and why."""
    return '; '.join(f'{view} left out ({why})' for view, why in sorted(left_out.items()))
