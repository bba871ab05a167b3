"""Recognise a dataset folder's format and open it with the right reader."""

from pathlib import Path

from matrix_core.datasets.matrix_reader import MatrixDataset
from matrix_core.datasets.site_reader import META_FILE as SITE_META_FILE
from matrix_core.datasets.site_reader import SITE_FILE, SiteDataset
from matrix_core.datasets.static_rig import MultiviewXDataset, WildtrackDataset
from matrix_core.datasets.types import DatasetError

# (reader, marker paths that identify the format)
_FORMATS = (
    (SiteDataset, (SITE_META_FILE, SITE_FILE)),
    (MatrixDataset, ('image_subsets', 'calibrations/intrinsic')),
    (WildtrackDataset, ('Image_subsets', 'calibrations/intrinsic_zero')),
    (MultiviewXDataset, ('Image_subsets', 'calibrations/intrinsic')),
)


def open_dataset(path):
    """Open a site dataset, MATRIX, Wildtrack or MultiviewX folder; raises :class:`DatasetError` saying why not."""
    root = Path(path)
    if not root.is_dir():
        raise DatasetError(f'dataset folder not found: {root}')
    names = {p.name for p in root.iterdir()}
    for reader, markers in _FORMATS:
        # Compare names exactly: 'image_subsets' (MATRIX) vs 'Image_subsets' (the others) tells them apart
        # even on case-insensitive file systems.
        if markers[0] in names and ((root / markers[1]).is_dir() or (root / markers[1]).is_file()):
            return reader(root)
    raise DatasetError(
        f'{root} is not a MATRIX, Wildtrack or MultiviewX folder or a site dataset: expected image_subsets/ + '
        f'calibrations/intrinsic/ (MATRIX), Image_subsets/ + calibrations/intrinsic_zero/ (Wildtrack) or '
        f'Image_subsets/ + calibrations/intrinsic/ (MultiviewX) or site_dataset.json + site.yaml (site dataset); '
        f'found {sorted(names)[:12]}'
    )
