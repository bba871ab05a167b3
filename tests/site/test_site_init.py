"""``matrix-tracker site init`` on a bag of the real MATRIX sample: each drone's reference calibration from the
boards is within a small tolerance of the sample's true calibration, the written site loads and its references
read back; a drone whose images show no board is reported and left out, the others are written."""

import numpy as np
import pytest
import yaml

from matrix_core.bags.reader import read_sequence_frames
from matrix_core.bags.writer import SequenceBagWriter
from matrix_core.cli.main import main
from matrix_core.datasets import MatrixDataset
from matrix_core.datasets.base import read_image
from matrix_core.geometry.camera import rotation_angle_deg
from matrix_core.site import load_site
from matrix_core.site.references import reference_camera, require_references
from matrix_core.site.shipped import SITES_DIR

DRONES = ('D1', 'D2')
BLANK = 'D3'  # its images are a flat grey: no board to see
FRAME = 0


@pytest.fixture(scope='module')
def recording(matrix_sample, tmp_path_factory):
    """(bag, boards description, true cameras) of one frame of D1, D2 (real images) and D3 (blank)."""
    ds = MatrixDataset(matrix_sample)
    frame = ds.frames[FRAME]
    truth = {v: ds.camera(v, frame) for v in (*DRONES, BLANK)}
    images = {v: read_image(ds.image_path(v, frame)) for v in DRONES}
    images[BLANK] = np.full_like(images[DRONES[0]], 128)
    folder = tmp_path_factory.mktemp('recording')
    with SequenceBagWriter(folder / 'bag', [*DRONES, BLANK], compressed=True) as bag:
        bag.write_frame(0, images, truth, {})
    site = yaml.safe_load((SITES_DIR / 'matrix.yaml').read_text())
    # A rough prior per drone, as a user would give it: the camera 1.5 m off, aimed 3 m off, no roll.
    priors = {}
    for v, cam in truth.items():
        aim = cam.backproject_to_ground([[cam.width / 2, cam.height / 2]])[0]
        priors[v] = {
            'position': [float(x) for x in cam.center + [1.0, -1.0, 0.5]],
            'look_at': [float(aim[0]) + 2.0, float(aim[1]) - 2.0, 0.0],
        }
    boards = {k: site[k] for k in ('area', 'cell_m', 'boards', 'obstacles')}
    (folder / 'boards.yaml').write_text(yaml.safe_dump({'name': 'square', **boards, 'priors': priors}))
    return folder / 'bag', folder / 'boards.yaml', truth


def test_site_init_calibrates_each_drone_and_leaves_out_the_one_that_saw_no_board(recording, tmp_path, capsys):
    bag, boards, truth = recording
    out = tmp_path / 'site'
    assert main(['site', 'init', '--bag', str(bag), '--boards', str(boards), '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    assert f'{BLANK}: left out: saw no board' in printed, printed
    for v in DRONES:
        assert f'{v}: reference frame 0 of 1 (t=1.000 s), ' in printed and ' px rms' in printed, printed

    site = load_site(out / 'site.yaml', require_references=True)
    assert site.drone_names == DRONES and site.name == 'square' and len(site.boards) == 2
    # each reference names the recorded frame it was taken from, by its header stamp
    (stamp_ns,) = [frame.stamp_ns for frame in read_sequence_frames(bag)]
    assert [site.drone(v).reference.stamp_s for v in DRONES] == [pytest.approx(stamp_ns * 1e-9)] * len(DRONES)
    require_references(site)
    for v in DRONES:
        got, want = reference_camera(site, site.drone(v)), truth[v]
        assert rotation_angle_deg(got.R, want.R) < 0.1, v
        assert np.linalg.norm(got.center - want.center) < 0.1, v
        assert np.allclose(got.K, want.K)


def test_site_init_refuses_an_existing_folder_and_writes_nothing_when_no_drone_sees_a_board(recording, tmp_path):
    bag, boards, _ = recording
    taken = tmp_path / 'taken'
    taken.mkdir()
    (taken / 'keep.txt').write_text('mine')
    assert main(['site', 'init', '--bag', str(bag), '--boards', str(boards), '--out', str(taken)]) == 2
    assert sorted(p.name for p in taken.iterdir()) == ['keep.txt']
    assert main(['site', 'init', '--bag', str(bag), '--boards', str(boards), '--out', str(bag / 'site')]) == 2
    assert not (bag / 'site').exists()
    # boards that are nowhere in the images: every drone is left out, and nothing is written
    data = yaml.safe_load(boards.read_text())
    for b in data['boards']:
        b['origin'][0] += 8.0  # still inside the area, far from where the cloth lies
    elsewhere = tmp_path / 'elsewhere.yaml'
    elsewhere.write_text(yaml.safe_dump(data))
    out = tmp_path / 'none'
    assert main(['site', 'init', '--bag', str(bag), '--boards', str(elsewhere), '--out', str(out)]) == 2
    assert not out.exists()


def test_a_board_outside_the_area_is_an_error_naming_it(recording, tmp_path, capsys):
    bag, boards, _ = recording
    data = yaml.safe_load(boards.read_text())
    data['boards'][1]['origin'] = [40.0, -5.25, 0.1]
    bad = tmp_path / 'bad.yaml'
    bad.write_text(yaml.safe_dump(data))
    assert main(['site', 'init', '--bag', str(bag), '--boards', str(bad), '--out', str(tmp_path / 'o')]) == 2
    assert 'bad.yaml: boards[1] (B): lies outside the area' in capsys.readouterr().err
