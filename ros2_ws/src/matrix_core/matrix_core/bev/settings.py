"""Settings of the BEV fusion network (shared by ``matrix-tracker train/evaluate`` and the ``fuse`` node)."""

from dataclasses import dataclass, field

from matrix_core.site.shipped import matrix_site


@dataclass
class BevSettings:
    """Grid, input resolution, model choice and decoding. Metres, pixels, probabilities."""

    model: str = field(default='bev_small', metadata={'help': 'model name in matrix_core.bev.registry.MODELS'})
    cell_m: float = field(
        default=matrix_site().cell_m,
        metadata={
            'help': "BEV cell size (m); the MATRIX site's 0.25 keeps a 30 m scene at 128x128 cells, fast on a CPU"
        },
    )
    margin_m: float = field(default=1.0, metadata={'help': 'grid margin (m) added around the dataset area'})
    area: list[float] = field(
        default_factory=list, metadata={'help': 'x_min y_min x_max y_max of the area (m); empty: from the dataset'}
    )
    image_width: int = field(default=480, metadata={'help': 'network input width (px); images are resized to it'})
    image_height: int = field(default=272, metadata={'help': 'network input height (px), a multiple of 8'})
    heatmap_sigma_m: float = field(default=0.3, metadata={'help': 'std (m) of the Gaussian centre-heatmap targets'})
    score_threshold: float = field(default=0.3, metadata={'help': 'decoded peaks below this heatmap score are dropped'})
    nms_radius_m: float = field(
        default=0.5, metadata={'help': 'peaks closer than this (m) are suppressed by max-pool NMS'}
    )
    max_detections: int = field(default=200, metadata={'help': 'keep at most this many peaks per frame'})
    subcell: str = field(
        default='heatmap',
        metadata={
            'help': "sub-cell position of a peak: 'heatmap' (3x3 score centroid, the most precise measured), "
            "'offset' (offset head) or 'none' (cell centre)"
        },
    )
    temporal: bool = field(default=True, metadata={'help': 'fuse the previous frame\'s BEV features'})

    def __post_init__(self):
        for name in ('cell_m', 'heatmap_sigma_m', 'nms_radius_m'):
            if not getattr(self, name) > 0:
                raise ValueError(f'{name} must be positive, got {getattr(self, name)}')
        if self.margin_m < 0:
            raise ValueError(f'margin_m must be >= 0, got {self.margin_m}')
        if self.area and len(self.area) != 4:
            raise ValueError(f'area needs 4 numbers x_min y_min x_max y_max, got {self.area}')
        if self.image_width % 8 or self.image_height % 8 or self.image_width <= 0 or self.image_height <= 0:
            raise ValueError(f'image size must be positive multiples of 8, got {self.image_width}x{self.image_height}')
        if self.subcell not in ('heatmap', 'offset', 'none'):
            raise ValueError(f"subcell must be 'heatmap', 'offset' or 'none', got {self.subcell!r}")
        if not 0 <= self.score_threshold <= 1 or self.max_detections < 1:
            raise ValueError('score_threshold must be in [0, 1] and max_detections >= 1')

    def grid(self, dataset_area=None):
        """The :class:`BevGrid` over ``area`` (or ``dataset_area``) plus the margin."""
        from matrix_core.geometry.grid import BevGrid

        area = self.area or dataset_area
        if not area:
            raise ValueError('no area: set BevSettings.area or pass the dataset area')
        x0, y0, x1, y1 = area
        m = self.margin_m
        return BevGrid(x0 - m, y0 - m, x1 + m, y1 + m, self.cell_m)
