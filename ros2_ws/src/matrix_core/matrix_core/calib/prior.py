"""A drone's first calibration prior: where the calibrator starts before its first good frame."""

from matrix_core.calib.scene import CalibScene
from matrix_core.datasets import DatasetError


def initial_prior(scene: CalibScene, view: str, reference=None) -> tuple:
    """(prior Camera, its (H, W, 3) BGR image or None) of ``view``: the reference calibration and image of
    ``reference`` (a MatrixDataset with ``reference/``) when it has them, else the config's initial pose.
    Raises :class:`DatasetError` saying why when there is neither."""
    why = []
    if reference is not None and reference.has_reference:
        try:
            return reference.reference_camera(view), reference.reference_image(view)
        except DatasetError as exc:
            why.append(f'no reference prior in {reference.root}: {exc}')
    if view in scene.initial_poses:
        return scene.initial_poses[view], None
    where = f'{reference.root} has no reference/calibrations and ' if reference is not None else ''
    raise DatasetError('; '.join(why + [f'no prior pose for {view}: {where}the config has no initial_poses.{view}']))
