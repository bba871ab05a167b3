"""Dataset readers and writers. ``open_dataset`` picks the right reader for a folder."""

from matrix_core.datasets.base import MultiviewDataset
from matrix_core.datasets.matrix_reader import MatrixDataset
from matrix_core.datasets.matrix_writer import MatrixWriter
from matrix_core.datasets.open import open_dataset
from matrix_core.datasets.site_reader import SiteDataset
from matrix_core.datasets.site_writer import SiteDatasetWriter
from matrix_core.datasets.static_rig import MultiviewXDataset, WildtrackDataset
from matrix_core.datasets.types import BoundingBox, DatasetError, PersonAnnotation, PlaneCorrespondences

__all__ = [
    'MultiviewDataset',
    'MatrixDataset',
    'MatrixWriter',
    'open_dataset',
    'SiteDataset',
    'SiteDatasetWriter',
    'WildtrackDataset',
    'MultiviewXDataset',
    'BoundingBox',
    'DatasetError',
    'PersonAnnotation',
    'PlaneCorrespondences',
]
