"""The shipped MATRIX site file holds what the code used for MATRIX before it was read from it: each value is
compared with one computed independently, from the real sample's own files where they state it (reference
calibrations and images, the markers of the marker grid and of the boards), else from the other definitions in
the code (the simulator's MATRIX variant, the shipped detector's grid)."""

import cv2
import numpy as np
import pytest

from matrix_core.bev.checkpoint import load_checkpoint
from matrix_core.bev.settings import BevSettings
from matrix_core.calib.scene import default_config_path, load_scene
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
    simulated = load_scene(default_config_path('sim_complex.yaml'))  # the simulator's camera of the MATRIX variant
    np.testing.assert_allclose(simulated.K, site.drones[0].camera.K)
    assert simulated.image_size == site.drones[0].camera.image_size


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


def _board_markers(dataset, frame: int) -> np.ndarray:
    """(M, 3) world metres of the Planes markers of ``frame`` that are not in ``3d.txt`` nor pedestrians (the
    boards' markers), triangulated from every view's 2-D file and the frame's stored calibrations."""
    central = set(np.loadtxt(dataset.root / 'matchings/Planes/3d.txt')[:, 1].astype(int))
    seen = {}
    for view in dataset.views:
        rows = np.loadtxt(dataset.root / f'matchings/Planes/Camera{conv.drone_number(view)}_2d_{frame:04d}.txt')
        for _, marker, u, v in rows:
            if int(marker) >= 40 and int(marker) not in central:
                seen.setdefault(int(marker), []).append((view, conv.pixels_from_file([[u, v]])[0]))
    points = []
    for views in seen.values():
        if len(views) >= 2:
            rows = [
                r
                for view, (u, v) in views
                for P in [dataset.camera(view, frame).P]
                for r in (u * P[2] - P[0], v * P[2] - P[1])
            ]
            X = np.linalg.svd(np.array(rows))[2][-1]
            points.append(X[:3] / X[3])
    return np.array(points)


def test_boards_are_where_the_sample_markers_are(site, dataset):
    # The sample's extra Planes markers are every second inner corner (i, j even) of the two boards.
    markers = _board_markers(dataset, 1)
    assert len(markers) == 200
    for board in site.boards:
        even = np.all(board.corner_indices() % 2 == 0, axis=1)
        distance = np.linalg.norm(board.corners_world()[:, None] - markers[None], axis=2).min(axis=1)
        assert np.all(distance[even] < 0.001) and np.all(distance[~even] > 0.1)


def test_board_colours_are_those_of_the_reference_images(site, dataset):
    # Projected into the empty reference images, the cells the site calls light are brighter than the dark
    # ones (a board behind the block shows no contrast; swapped colours would show a negative one).
    contrast = []
    for view in dataset.views:
        camera = dataset.reference_camera(view)
        grey = cv2.cvtColor(dataset.reference_image(view), cv2.COLOR_BGR2GRAY).astype(float)
        for board in site.boards:
            a, b = (v.ravel() for v in np.meshgrid(np.arange(board.nx + 1), np.arange(board.ny + 1)))
            uv = camera.project(board.points(a - 0.5, b - 0.5))
            ok = camera.in_image(uv, 2)
            values = grey[np.round(uv[ok, 1]).astype(int), np.round(uv[ok, 0]).astype(int)]
            sign = board.cell_sign(a[ok], b[ok])
            contrast.append(values[sign > 0].mean() - values[sign < 0].mean())
    assert min(contrast) > -20 and np.median(contrast) > 100


def test_boards_are_the_simulators(site):
    # The simulator's MATRIX variant gives the same boards by their outer corner and square count.
    for ours, sim in zip(site.boards, load_scene_config('complex').boards, strict=True):
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
