"""A site's values go into every component's settings by field name; the MATRIX site changes no default."""

import pytest

from matrix_core.bev.settings import BevSettings
from matrix_core.datasets import MatrixDataset
from matrix_core.fusion.image_boxes import ImageBoxSettings
from matrix_core.fusion.settings import FuseSettings
from matrix_core.register.settings import RegisterSettings
from matrix_core.site import load_site, matrix_site, site_path
from matrix_core.site.settings import apply_site, site_fields

SETTINGS = [FuseSettings, RegisterSettings, ImageBoxSettings]


@pytest.mark.parametrize('cls', SETTINGS, ids=lambda c: c.__name__)
def test_the_matrix_site_leaves_every_default_as_it_is(cls):
    assert site_fields(cls)  # each of these takes something from a site
    assert apply_site(cls(), matrix_site()) == cls()


def test_the_matrix_site_gives_the_bev_grid_of_a_matrix_dataset(matrix_sample):
    # BevSettings' empty area means "the dataset's"; with the MATRIX site's the grid is the same.
    assert site_fields(BevSettings) == ('cell_m', 'area')
    assert apply_site(BevSettings(), matrix_site()).grid() == BevSettings().grid(MatrixDataset(matrix_sample).area)


def test_the_plaza_site_sets_area_drones_obstacles_and_cell():
    plaza = load_site(site_path('plaza'))
    fuse = apply_site(FuseSettings(), plaza)
    assert fuse.area == [-24.0, -12.0, 24.0, 12.0]
    assert fuse.views == ['alpha', 'bravo', 'charlie', 'delta', 'echo']
    assert fuse.image_kind == FuseSettings().image_kind  # the rest is untouched
    assert apply_site(RegisterSettings(), plaza).exclude_boxes == [6.0, -6.0, 10.0, -2.0, 4.0]
    assert apply_site(ImageBoxSettings(), plaza).obstacle_boxes == [6.0, -6.0, 10.0, -2.0, 4.0]
    bev = apply_site(BevSettings(), plaza)
    assert bev.cell_m == plaza.cell_m and bev.grid(plaza.area).shape == plaza.grid_shape(bev.margin_m)
