"""What a drone of the live graph reads at start-up, from the dataset folder or the site file's references
(:func:`open_references`), checked before anything starts.

Every drone's ``register`` reads its reference image and calibration, its ``calib`` takes its first prior
from that calibration, and ``fuse`` the reference intrinsics (``fusion.image_outputs.ViewCameras``). A drone
whose files cannot be read would end its own process and fuse's at start; :func:`unreadable_drones` names it
and why, so that the graph can leave it out and run the others.
"""

from pathlib import Path

from matrix_core.datasets.types import DatasetError


def open_references(dataset: str = '', site=None):
    """The source of a drone's references at start-up: the dataset folder ``dataset`` (a MATRIX folder, or a
    site dataset: ``site_dataset.json`` beside its ``site.yaml``), else, with ``site`` (a
    :class:`~matrix_core.site.schema.Site`), that site file's references; None with neither. Every source has
    ``reference_image(view)``, ``reference_camera(view)``, ``has_reference``, ``area`` and ``root``.
    :class:`DatasetError` when the folder cannot be opened or the site has no references."""
    if dataset:
        from matrix_core.datasets.matrix_reader import MatrixDataset
        from matrix_core.datasets.site_reader import META_FILE, SiteDataset

        return SiteDataset(dataset) if (Path(dataset) / META_FILE).is_file() else MatrixDataset(dataset)
    if site is None:
        return None
    from matrix_core.site.load import SiteError
    from matrix_core.site.references import SiteReferences

    try:
        return SiteReferences(site)
    except SiteError as exc:
        raise DatasetError(str(exc)) from None


def unreadable_drones(dataset, views) -> dict:
    """view -> why its start-up inputs cannot be used, for each of ``views`` whose reference image (decoded
    and checked whole: ``datasets.base.read_image``) or reference calibration cannot be read from ``dataset``
    (a source of :func:`open_references`); the others are not in it."""
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
