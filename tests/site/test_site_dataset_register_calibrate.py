"""``matrix-tracker register`` and ``matrix-tracker calibrate`` on a site dataset: drones with names of their own
and cameras that differ (image size and focal length), the site's boards, each drone's references from the
dataset's site.yaml. The records are named by drone; the calibrations come out as a site dataset that
``open_dataset`` reads, each frame close to the simulator's truth."""

import csv
import json

import pytest
import yaml

from matrix_core.calib.evaluation import pose_errors
from matrix_core.cli.main import main
from matrix_core.datasets import SiteDataset, open_dataset
from matrix_core.site import site_path

pytestmark = pytest.mark.slow
DRONES = ('north_cam', 'east_cam')


@pytest.fixture(scope='module')
def site_dataset(tmp_path_factory):
    """Two of the plaza's drones, one with a smaller, longer-focus camera than the other; two frames."""
    tmp = tmp_path_factory.mktemp('site')
    site = yaml.safe_load(site_path('plaza').read_text())
    first, second = dict(site['drones'][0]), dict(site['drones'][3])
    second['camera'] = {'image_size': [960, 540], 'K': [800.0, 0.0, 479.5, 0.0, 800.0, 269.5, 0.0, 0.0, 1.0]}
    site.update(name='pair', drones=[{**first, 'name': DRONES[0]}, {**second, 'name': DRONES[1]}])
    (tmp / 'pair.yaml').write_text(yaml.safe_dump(site, sort_keys=False))
    data = tmp / 'pair'
    args = ['simulate', '--site', str(tmp / 'pair.yaml'), '--frames', '2', '--config', 'simple', '--out', str(data)]
    assert main(args) == 0
    return data


def test_register_and_calibrate_a_site_dataset(site_dataset, tmp_path, capsys):
    dataset = open_dataset(site_dataset)
    assert {dataset.view_image_size(v) for v in DRONES} == {(1280, 720), (960, 540)}
    reg = tmp_path / 'reg'
    assert main(['register', str(site_dataset), '--out', str(reg)]) == 0
    records = sorted(p.name for p in (reg / 'registration').glob('*_[0-9][0-9][0-9][0-9].json'))
    assert records == sorted(f'{d}_{f:04d}.json' for d in DRONES for f in (0, 1))
    assert all(json.loads((reg / 'registration' / r).read_text())['status'] == 'ok' for r in records)
    summary = json.loads((reg / 'registration' / 'summary.json').read_text())
    assert summary['stats']['failed'] == 0 and summary['stats']['raised'] == 0, summary['stats']

    out = tmp_path / 'cal'
    assert main(['calibrate', str(site_dataset), '--out', str(out), '--registration', str(reg)]) == 0
    with open(out / 'calibration_status.csv', newline='') as fh:
        rows = list(csv.DictReader(fh))
    assert [(r['view'], r['status'], r['guide']) for r in rows] == [
        (d, 'ok', 'registration') for d in DRONES for _ in (0, 1)
    ], rows
    calibrated = open_dataset(out)
    assert isinstance(calibrated, SiteDataset) and calibrated.views == DRONES and calibrated.frames == (0, 1)
    for view in DRONES:
        assert calibrated.has_reference and calibrated.reference_camera(view).width == dataset.view_image_size(view)[0]
        for frame in (0, 1):
            rot_deg, centre_m = pose_errors(calibrated.camera(view, frame), dataset.camera(view, frame))
            assert rot_deg < 0.3 and centre_m < 0.2, (view, frame, rot_deg, centre_m)
