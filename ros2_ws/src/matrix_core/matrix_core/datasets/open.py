"""Recognise a dataset folder's format and open it with the right reader."""

from pathlib import Path

from matrix_core.datasets.matrix_reader import MatrixDataset
from matrix_core.datasets.static_rig import MultiviewXDataset, WildtrackDataset
from matrix_core.datasets.types import DatasetError

# (reader, marker paths that identify the format)
_FORMATS = (
    (MatrixDataset, ('image_subsets', 'calibrations/intrinsic')),
    (WildtrackDataset, ('Image_subsets', 'calibrations/intrinsic_zero')),
    (MultiviewXDataset, ('Image_subsets', 'calibrations/intrinsic')),
)


def open_dataset(path):
    """Open a MATRIX, Wildtrack or MultiviewX folder; raises :class:`DatasetError` saying why not."""
    root = Path(path)
    if not root.is_dir():
        raise DatasetError(f'dataset folder not found: {root}')
    names = {p.name for p in root.iterdir()}
    for reader, markers in _FORMATS:
        # Compare names exactly: 'image_subsets' (MATRIX) vs 'Image_subsets' (the others) tells them apart
        # even on case-insensitive file systems.
        if markers[0] in names and (root / markers[1]).is_dir():
            return reader(root)
    raise DatasetError(
        f'{root} is not a MATRIX, Wildtrack or MultiviewX folder: expected image_subsets/ + '
        f'calibrations/intrinsic/ (MATRIX), Image_subsets/ + calibrations/intrinsic_zero/ (Wildtrack) or '
        f'Image_subsets/ + calibrations/intrinsic/ (MultiviewX); found {sorted(names)[:12]}'
    )
