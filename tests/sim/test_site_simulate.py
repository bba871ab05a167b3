"""`matrix-tracker simulate --site`: any site file becomes a site dataset (metric positions, the site's drones,
cameras, boards and obstacles, rendered references) that info, bag, evaluate and the site loader read."""

import json

import numpy as np
import pytest

from matrix_core.bags import read_sequence_frames
from matrix_core.calib.board import Checkerboard
from matrix_core.cli.main import main
from matrix_core.datasets import SiteDataset, open_dataset
from matrix_core.datasets.summary import summarize
from matrix_core.sim.site_rig import board_config
from matrix_core.site import load_site, site_path
from matrix_core.site.references import require_references

YARD = """version: 1
name: yard
area: [100.0, 40.0, 130.0, 60.0]
cell_m: 0.5
references: {source: simulate}
drones:
  - name: north
    camera: {image_size: [400, 300], K: [300.0, 0.0, 199.5, 0.0, 300.0, 149.5, 0.0, 0.0, 1.0]}
    altitude_m: 16.0
    home: [115.0, 72.0]
  - name: east_2
    camera: {image_size: [320, 180], K: [228.5, 0.0, 159.5, 0.0, 228.5, 89.5, 0.0, 0.0, 1.0]}
  - name: Low
    camera: {image_size: [320, 180], K: [228.5, 0.0, 159.5, 0.0, 228.5, 89.5, 0.0, 0.0, 1.0]}
    altitude_m: 9.0
boards:
  - {name: mat, origin: [104.0, 50.0, 0.0], square: 0.3, inner_corners: [9, 6], axis_i: [0.0, 1.0, 0.0],
     axis_j: [1.0, 0.0, 0.0], first_cell_light: false}
obstacles:
  - {name: shed, footprint: [120.0, 44.0, 124.0, 47.0], height: 3.0}
"""


def _simulate(out, site, *extra):
    argv = ['simulate', '--site', str(site), '--config', 'simple', '--frames', '2', '--seed', '4', '--out', str(out)]
    assert main([*argv, *extra]) == 0
    return out


@pytest.fixture(scope='module')
def plaza(tmp_path_factory):
    return _simulate(tmp_path_factory.mktemp('plaza') / 'sim', 'plaza', '--image_scale', '0.2')


@pytest.fixture(scope='module')
def yard(tmp_path_factory):
    folder = tmp_path_factory.mktemp('yard')
    (folder / 'yard.yaml').write_text(YARD)
    return _simulate(folder / 'sim', folder / 'yard.yaml', '--altitude', '14', '--ring_radius', '25', '--bag', 'true')


def test_plaza_dataset_is_read_with_the_sites_drones_and_area(plaza):
    ds = open_dataset(plaza)
    assert isinstance(ds, SiteDataset)
    info = summarize(ds)
    assert info['format'] == 'site' and info['views'] == ['alpha', 'bravo', 'charlie', 'delta', 'echo']
    assert info['frames'] == 2 and info['image_size'] == [256, 144] and info['area_m'] == [-24.0, -12.0, 24.0, 12.0]
    assert info['has_reference'] and info['people'] == 10 and info['visible_boxes'] > 0
    assert main(['info', str(plaza)]) == 0
    # every drone flew around its home at about its altitude (plaza.yaml: 17.5 to 18.5 m, +-0.5 m band)
    heights = [ds.camera(v, f).center[2] for v in ds.views for f in ds.frames]
    assert 16.9 < min(heights) and max(heights) < 19.1


def test_annotations_are_metric_and_inside_the_area(plaza):
    ds = open_dataset(plaza)
    x0, y0, x1, y1 = ds.area
    for frame in ds.frames:
        persons = ds.annotations(frame)
        assert len(persons) == 10
        for p in persons:
            assert x0 < p.world_xy[0] < x1 and y0 < p.world_xy[1] < y1
            for view, box in p.boxes.items():  # the box stands on the person's projected position
                foot = ds.camera(view, frame).project(np.array([[*p.world_xy, 0.0]]))[0]
                assert box.xmin < foot[0] < box.xmax and abs(box.ymax - foot[1]) < 0.01
        assert ds.pedestrian_positions(frame).keys() == {p.person_id for p in persons}


def test_the_dataset_site_file_has_every_drones_reference(plaza):
    site = load_site(plaza / 'site.yaml')
    assert site.references.value == 'files' and site.references_root == plaza.resolve()
    require_references(site)  # every image and calibration exists, images of the camera's size
    ds = open_dataset(plaza)
    for view in ds.views:
        ref = ds.reference_camera(view)
        assert (ref.width, ref.height) == (256, 144)
        assert ds.reference_image(view).shape == (144, 256, 3)
    # the original plaza site is unchanged and still has no references of its own
    assert load_site(site_path('plaza')).references.value == 'simulate'


def test_board_corners_project_where_the_dataset_says(plaza):
    ds = open_dataset(plaza)
    assert len(ds.plane_markers) == 19 * 19 * 2 + 15 * 11
    seen = 0
    for view in ds.views:
        pc = ds.plane_correspondences(view, 1)
        if len(pc.marker_ids):
            uv = ds.camera(view, 1).project(pc.world_xyz)
            np.testing.assert_allclose(uv, pc.image_uv, atol=1e-3)
            seen += 1
    assert seen >= 3


def test_simulated_boards_have_the_sites_squares_and_colours():
    site = load_site(site_path('matrix'))  # its boards run along -y
    boards = [*site.boards, *load_site(site_path('plaza')).boards]
    boards.append(Checkerboard('turned', (2.0, 3.0, 0.0), 0.5, (4, 7), (0.0, -1.0, 0.0), (-1.0, 0.0, 0.0), False))
    for board in boards:
        cfg = board_config(board)
        a, b = np.meshgrid(np.arange(board.nx + 1), np.arange(board.ny + 1))
        centres = board.points(a.ravel() - 0.5, b.ravel() - 0.5)[:, :2]
        ij = np.floor((centres - cfg.origin) / cfg.square_m + 1e-9).astype(int)
        assert np.all((ij >= 0) & (ij < cfg.squares_xy)), board.name
        dark = (ij.sum(axis=1) + cfg.dark_parity) % 2 == 0
        np.testing.assert_array_equal(board.cell_sign(a.ravel(), b.ravel()) < 0, dark, err_msg=board.name)
    tilted = Checkerboard('tilted', (0.0, 0.0, 0.0), 0.5, (4, 4), (0.6, 0.8, 0.0), (-0.8, 0.6, 0.0))
    with pytest.raises(ValueError, match='tilted.*ground axes'):
        board_config(tilted)


def test_three_drone_site_at_another_origin(yard):
    ds = open_dataset(yard)
    assert ds.views == ('north', 'east_2', 'Low') and ds.area == (100.0, 40.0, 130.0, 60.0)
    sizes = {v: (ds.camera(v, 0).width, ds.camera(v, 0).height) for v in ds.views}
    assert sizes == {'north': (400, 300), 'east_2': (320, 180), 'Low': (320, 180)}
    assert {v: ds.load_image(v, 1).shape[:2] for v in ds.views} == {
        'north': (300, 400),
        'east_2': (180, 320),
        'Low': (180, 320),
    }
    written = load_site(yard / 'site.yaml')
    homes = {d.name: (*d.home_xy, d.altitude_m) for d in written.drones}
    assert homes['north'] == (115.0, 72.0, 16.0)
    centre = np.array([115.0, 50.0])
    for name, altitude in (('east_2', 14.0), ('Low', 9.0)):  # on the ring of --ring_radius at --altitude / altitude_m
        assert np.linalg.norm(np.array(homes[name][:2]) - centre) == pytest.approx(25.0)
        assert homes[name][2] == altitude
    for frame in ds.frames:
        for p in ds.annotations(frame):
            assert 100.0 < p.world_xy[0] < 130.0 and 40.0 < p.world_xy[1] < 60.0
            assert not (120.0 < p.world_xy[0] < 124.0 and 44.0 < p.world_xy[1] < 47.0)  # nobody inside the shed
    assert len(ds.plane_markers) == 9 * 6
    # the bag written with it: the site's drone names as namespaces, every person's position
    frames = list(read_sequence_frames(yard / 'bag'))
    assert len(frames) == 2 and set(frames[0].images) == {'north', 'east_2', 'Low'}
    assert frames[1].images['north'].shape == (300, 400, 3)


def test_bag_and_evaluate_read_the_site_dataset(plaza, tmp_path):
    assert main(['bag', str(plaza), '--out', str(tmp_path / 'bag')]) == 0
    frames = list(read_sequence_frames(tmp_path / 'bag'))
    ds = open_dataset(plaza)
    assert len(frames) == 2 and set(frames[0].images) == set(ds.views)
    np.testing.assert_array_equal(frames[1].images['charlie'], ds.load_image('charlie', 1))
    out = tmp_path / 'evaluate'
    argv = ['evaluate', str(plaza), '--checkpoint', 'detector_tiny_seed0.pt', '--out', str(out), '--heatmaps', '1']
    assert main([*argv, '--device', 'cpu']) == 0
    metrics = json.loads((out / 'metrics.json').read_text())
    assert metrics['views'] == list(ds.views)
    gt = np.loadtxt(out / 'ground_truth.txt', ndmin=2)
    assert len(gt) == 20  # both frames, every person (all inside the plaza)
    assert set(metrics['image_plane']) == {*ds.views, 'all'}  # scored in every drone's image


def test_width_and_height_are_the_sites_not_flags(tmp_path):
    argv = ['simulate', '--site', 'plaza', '--width', '640', '--height', '360', '--out', str(tmp_path / 'x')]
    assert main(argv) == 2  # refused, naming image_scale
    assert not (tmp_path / 'x').exists()


def test_without_a_site_simulate_writes_exactly_what_the_matrix_writer_writes(tmp_path):
    """The MATRIX path (no --site) is the MATRIX writer's: the command's files are byte for byte those of the
    simulation written here step by step with MatrixWriter, and no site dataset file is among them."""
    from matrix_core.datasets import MatrixWriter
    from matrix_core.sim.config import load_scene_config, scene_config_to_dict
    from matrix_core.sim.sequence import Simulation, write_frame, write_summary

    cli = tmp_path / 'cli'
    argv = ['simulate', '--config', 'complex', '--frames', '2', '--seed', '9', '--width', '320', '--height', '180']
    assert main([*argv, '--out', str(cli)]) == 0
    by_hand = tmp_path / 'by_hand'
    config = load_scene_config('complex')
    sim = Simulation(config, 9, 320, 180)
    simulator = {'config': scene_config_to_dict(config), 'seed': 9, 'frame_period': 0.5, 'replay': None}
    writer = MatrixWriter(by_hand, tuple(config.area), '.png', {'simulator': simulator, 'image_size': [320, 180]})
    writer.write_plane_markers({int(i): p for i, p in zip(sim.scene.marker_ids, sim.scene.marker_xyz)})
    for k, view in enumerate(sim.views):
        cam, img = sim.render_reference(k)
        writer.write_image(view, 0, img, reference=True)
        writer.write_camera(view, 0, cam, reference=True)
    for frame in range(2):
        if frame:
            sim.step(0.5)
        write_frame(sim, writer, frame, by_hand)
    write_summary(by_hand, 2, [0, 1], {})
    files = sorted(p.relative_to(cli) for p in cli.rglob('*') if p.is_file())
    assert files == sorted(p.relative_to(by_hand) for p in by_hand.rglob('*') if p.is_file())
    assert len(files) > 100 and not any(f.name in ('site.yaml', 'site_dataset.json') for f in files)
    for f in files:
        assert (cli / f).read_bytes() == (by_hand / f).read_bytes(), f
