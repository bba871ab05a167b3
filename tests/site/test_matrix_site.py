"""The shipped MATRIX site file holds what the code used for MATRIX before it was read from it: each value is
compared with one computed independently, from the real sample's own files where they state it (reference
calibrations and images, the marker grid under the block), else from the other definitions in the code (the
calibrator's board config, the simulator's MATRIX variant, the shipped detector's grid)."""

import numpy as np
import pytest

from matrix_core.bev.checkpoint import load_checkpoint
from matrix_core.bev.settings import BevSettings
from matrix_core.calib.scene import load_scene
from matrix_core.datasets import MatrixDataset
from matrix_core.datasets import matrix_conventions as conv
from matrix_core.fusion.settings import FuseSettings, shipped_checkpoint
from matrix_core.register.settings import MATRIX_BLOCK, RegisterSettings
from matrix_core.sim.config import load_scene_config
from matrix_core.site import ReferenceSource, load_site, matrix_site
from matrix_core.site.references import reference_camera, reference_files, require_references
from matrix_core.site.shipped import SITES_DIR


@pytest.fixture(scope='module')
def site(matrix_sample):
    """The shipped MATRIX site with its references root pointed at this machine's sample."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv('MATRIX_SHARED', str(matrix_sample.parent))
        return load_site(SITES_DIR / 'matrix.yaml', require_references=True)


@pytest.fixture(scope='module')
def dataset(matrix_sample):
    return MatrixDataset(matrix_sample)


def _planes_markers(dataset) -> np.ndarray:
    """(101, 3) internal world metres of the central marker grid of ``matchings/Planes/3d.txt``."""
    rows = np.loadtxt(dataset.root / 'matchings/Planes/3d.txt')
    return conv.planes_3d_from_file(rows[:, 2:5])


def test_the_code_reads_its_matrix_defaults_from_the_shipped_site():
    s = matrix_site()
    assert conv.MATRIX_AREA == s.area
    assert conv.MATRIX_VIEWS == s.drone_names
    assert MATRIX_BLOCK == s.obstacle_boxes
    assert BevSettings().cell_m == s.cell_m
    assert FuseSettings().area == list(s.area) and FuseSettings().views == list(s.drone_names)
    assert RegisterSettings().exclude_boxes == s.obstacle_boxes


def test_drones_are_the_sample_views(site, dataset):
    assert site.drone_names == dataset.views
    assert len(site.drones) == 8


def test_area_is_the_position_grid_centred_on_the_scene(site, dataset):
    x0, y0, x1, y1 = site.area
    side = conv.POSITION_GRID_COLS * conv.POSITION_CELL_M  # the positionID grid of the file format
    assert (x1 - x0, y1 - y0) == pytest.approx((side, side))
    # The marker grid (with its extra marker in the middle) and the ring of reference poses are centred on
    # the square.
    assert ((x0 + x1) / 2, (y0 + y1) / 2) == pytest.approx(tuple(_planes_markers(dataset)[:, :2].mean(axis=0)))
    centres = np.array([dataset.reference_camera(v).center for v in dataset.views])
    assert ((x0 + x1) / 2, (y0 + y1) / 2) == pytest.approx(tuple(centres[:, :2].mean(axis=0)), abs=0.2)
    assert dataset.area == site.area


def test_cell_is_the_shipped_detectors(site):
    assert load_checkpoint(shipped_checkpoint())['settings']['cell_m'] == site.cell_m


def test_cameras_are_the_reference_calibrations(site, dataset):
    for d in site.drones:
        ref = dataset.reference_camera(d.name)
        assert d.camera.image_size == (ref.width, ref.height)
        # The stored K is an ideal pinhole refined by calibrateCamera: it varies in the 4th decimal.
        np.testing.assert_allclose(d.camera.K, ref.K, atol=0.05)
        np.testing.assert_allclose(d.camera.dist, 0.0)
    np.testing.assert_allclose(load_scene().K, site.drones[0].camera.K)  # the calibrator's config
    assert load_scene().image_size == site.drones[0].camera.image_size


def test_references_are_the_sample_reference_folder(site, dataset):
    assert site.references is ReferenceSource.FILES
    files = reference_files(site)
    assert [f.drone for f in files] == list(dataset.views) and all(f.found for f in files)
    for f, d in zip(files, site.drones):
        assert f.image == dataset.reference_image_path(d.name).resolve()
        ours, theirs = reference_camera(site, d), dataset.reference_camera(d.name)
        np.testing.assert_allclose(ours.K, theirs.K)
        np.testing.assert_allclose(ours.cam_T_world, theirs.cam_T_world)
    require_references(site)


def _corner_set(points) -> np.ndarray:
    return np.array(sorted(map(tuple, np.round(points, 9))))


def test_boards_are_the_calibrators_and_the_simulators(site):
    calib = load_scene().boards
    assert [b.name for b in site.boards] == [b.name for b in calib]
    assert list(site.boards) == list(calib)
    # The simulator's MATRIX variant gives the same boards by their outer corner and square count.
    for ours, sim in zip(site.boards, load_scene_config('complex').boards):
        k = np.arange(1, sim.squares)
        i, j = np.meshgrid(k, k)
        sim_corners = np.c_[
            sim.origin[0] + sim.square_m * i.ravel(), sim.origin[1] + sim.square_m * j.ravel(), np.full(i.size, sim.z)
        ]
        np.testing.assert_allclose(_corner_set(ours.corners_world()), _corner_set(sim_corners), atol=1e-9)


def test_the_block_covers_the_marker_grid_it_stands_on(site, dataset):
    (block,) = site.obstacles
    x0, y0, x1, y1 = block.footprint
    markers = _planes_markers(dataset)
    assert np.all((markers[:, 0] > x0) & (markers[:, 0] < x1) & (markers[:, 1] > y0) & (markers[:, 1] < y1))
    # The marker grid is 0.5 m spaced and the block overhangs it by half a spacing on each side.
    assert (markers[:, 0].min() - x0, x1 - markers[:, 0].max()) == pytest.approx((0.25, 0.25))
    sim_block = load_scene_config('complex').block
    assert sim_block.bounds == pytest.approx(block.footprint)
    # Taller than every drone flies: the reference cameras are at about 12.3 m.
    assert block.height > max(dataset.reference_camera(v).center[2] for v in dataset.views)
