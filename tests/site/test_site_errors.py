"""A bad site file is one error naming the file, the key and the fault, raised before anything starts."""

import copy
import re
from pathlib import Path

import pytest
import yaml

from matrix_core.site import SiteError, load_site
from matrix_core.site.references import require_references
from matrix_core.site.shipped import SITES_DIR

CAMERA = {'image_size': [640, 480], 'K': [500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0]}


def _good() -> dict:
    """A small valid site: a 20 x 10 m area, two drones with reference files (written by ``_write``)."""
    return {
        'version': 1,
        'name': 'yard',
        'area': [0.0, 0.0, 20.0, 10.0],
        'cell_m': 0.5,
        'references': {'source': 'files', 'root': 'refs'},
        'drones': [
            {
                'name': name,
                'camera': dict(CAMERA),
                'reference': {
                    'image': f'{name}.png',
                    'calibration': {'format': 'matrix_xml', 'intrinsic': f'{name}_i.xml', 'extrinsic': f'{name}_e.xml'},
                },
            }
            for name in ('north', 'south')
        ],
        'boards': [{'name': 'A', 'origin': [2.25, 2.25, 0.0], 'square': 0.25, 'inner_corners': [7, 7]}],
        'obstacles': [{'name': 'shed', 'footprint': [12.0, 4.0, 14.0, 6.0], 'height': 3.0}],
    }


def _write(tmp_path: Path, data: dict) -> Path:
    path = tmp_path / 'yard.yaml'
    path.write_text(yaml.safe_dump(data))
    return path


def _error(tmp_path: Path, data: dict) -> str:
    path = _write(tmp_path, data)
    with pytest.raises(SiteError) as info:
        load_site(path)
    message = str(info.value)
    assert message.startswith(f'{path.resolve()}: '), message  # every error names the file first
    assert '\n' not in message
    return message


def test_the_good_site_loads(tmp_path):
    site = load_site(_write(tmp_path, _good()))
    assert site.drone_names == ('north', 'south')
    assert site.grid_shape() == (20, 40)
    assert site.references_root == (tmp_path / 'refs').resolve()
    assert site.obstacle_boxes == [12.0, 4.0, 14.0, 6.0, 3.0]


def test_unknown_key_is_named_with_the_allowed_ones(tmp_path):
    data = _good()
    data['cell_size'] = data.pop('cell_m')
    message = _error(tmp_path, data)
    assert "unknown key 'cell_size'" in message and 'allowed: area, boards, cell_m, drones' in message
    data = _good()
    data['drones'][1]['camera']['focal'] = 500.0
    message = _error(tmp_path, data)
    assert re.search(r": drones\[1\] \(south\)\.camera: unknown key 'focal' \(allowed: K, dist, image_size\)$", message)


def test_board_outside_the_area_is_named_with_its_extent(tmp_path):
    data = _good()
    data['boards'][0]['origin'] = [18.5, 2.25, 0.0]  # its outer edge reaches x = 20.25
    message = _error(tmp_path, data)
    assert ': boards[0] (A): lies outside the area [0.0, 0.0, 20.0, 10.0]' in message
    assert 'x 18.25..20.25' in message


def test_drone_without_a_reference_is_an_error_when_the_site_says_files(tmp_path):
    data = _good()
    del data['drones'][1]['reference']
    message = _error(tmp_path, data)
    assert ': drones[1] (south): no reference (references.source is files' in message
    # A site whose references are to be simulated loads without them ...
    data['references'] = {'source': 'simulate'}
    del data['drones'][0]['reference']
    site = load_site(_write(tmp_path, data))
    # ... and a command that needs them refuses it.
    with pytest.raises(SiteError, match=r': references.source: simulate: .* this command needs them'):
        require_references(site)


def test_missing_reference_file_is_an_error_for_a_command_that_needs_it(tmp_path):
    site = load_site(_write(tmp_path, _good()))  # loading reads no reference file
    with pytest.raises(SiteError, match=r': drones\[0\] \(north\)\.reference: no such file .*refs/north\.png$'):
        require_references(site)
    with pytest.raises(SiteError, match=r': drones\[0\] \(north\)\.reference: no such file'):
        load_site(_write(tmp_path, _good()), require_references=True)


def test_duplicate_drone_is_named_with_both_entries(tmp_path):
    data = _good()
    data['drones'][1]['name'] = 'north'
    assert ": drones: duplicate drone name 'north' (entries 0 and 1)" in _error(tmp_path, data)


def test_seventeen_drones_are_too_many(tmp_path):
    data = _good()
    data['drones'] = [dict(copy.deepcopy(data['drones'][0]), name=f'd{i}') for i in range(17)]
    assert ': drones: a site has 1 to 16 drones, got 17' in _error(tmp_path, data)
    data['drones'] = data['drones'][:16]
    assert len(load_site(_write(tmp_path, data)).drones) == 16
    data['drones'] = []
    assert ': drones: a site has 1 to 16 drones, got 0' in _error(tmp_path, data)


@pytest.mark.parametrize(
    'change, where',
    [
        (lambda d: d.update(cell_m='fine'), r": cell_m: expected a number, got str 'fine'"),
        (lambda d: d.update(cell_m=0), r': cell_m: must be positive, got 0'),
        (lambda d: d.update(area=[0, 0, 20]), r': area: expected a list of 4 numbers'),
        (
            lambda d: d.update(area=[20, 0, 0, 10]),
            r': area: expected \[x_min, y_min, x_max, y_max\] with x_min < x_max',
        ),
        (
            lambda d: d['drones'][0]['camera'].update(image_size=[640.5, 480]),
            r'drones\[0\] \(north\)\.camera\.image_size',
        ),
        (
            lambda d: d['drones'][0]['camera'].update(K=[1, 2, 3]),
            r'drones\[0\] \(north\)\.camera\.K: expected a list of 9',
        ),
        (lambda d: d['drones'][0].update(altitude_m=True), r'drones\[0\] \(north\)\.altitude_m: expected a number'),
        (lambda d: d['drones'][0].update(name='3rd drone'), r'drones\[0\]\.name: expected a name of letters'),
        (
            lambda d: d['drones'][0]['reference'].update(stamp_s='noon'),
            r"drones\[0\] \(north\)\.reference\.stamp_s: expected a number, got str 'noon'",
        ),
        (lambda d: d['boards'][0].update(square=-0.25), r'boards\[0\] \(A\)\.square: must be positive'),
        (
            lambda d: d['boards'][0].update(first_cell_light='yes'),
            r'boards\[0\] \(A\)\.first_cell_light: expected true',
        ),
        (lambda d: d['obstacles'][0].update(height='tall'), r'obstacles\[0\] \(shed\)\.height: expected a number'),
        (lambda d: d['references'].update(source='bag'), r'references\.source: expected one of files, simulate'),
        (lambda d: d.update(version=2), r': version: this matrix-tracker reads site files of version 1, got 2'),
        (lambda d: d.pop('area'), r": missing 'area'"),
    ],
)
def test_bad_type_or_range_names_the_key(tmp_path, change, where):
    data = _good()
    change(data)
    assert re.search(where, _error(tmp_path, data))


def test_unset_variable_in_the_references_root_is_named_when_needed(tmp_path, monkeypatch):
    monkeypatch.delenv('SITE_TEST_UNSET', raising=False)
    data = _good()
    data['references']['root'] = '${SITE_TEST_UNSET}/refs'
    site = load_site(_write(tmp_path, data))
    assert site.references_root is None
    with pytest.raises(SiteError, match=r'references\.root: .* names the environment variable SITE_TEST_UNSET'):
        require_references(site)
    monkeypatch.setenv('SITE_TEST_UNSET', str(tmp_path))
    assert load_site(_write(tmp_path, data)).references_root == (tmp_path / 'refs').resolve()


def test_not_yaml_is_named(tmp_path):
    path = tmp_path / 'broken.yaml'
    path.write_text('area: [0, 0\n')
    with pytest.raises(SiteError, match=r'broken\.yaml: not valid YAML'):
        load_site(path)


def test_the_shipped_plaza_site():
    site = load_site(SITES_DIR / 'plaza.yaml')
    x0, y0, x1, y1 = site.area
    assert (x1 - x0, y1 - y0) == (48.0, 24.0)
    assert len(site.drones) == 5 and len(site.boards) == 3 and len(site.obstacles) == 1
    assert all(d.camera.image_size == (1280, 720) for d in site.drones)
    assert all(abs(d.altitude_m - 18.0) <= 1.0 for d in site.drones)
    assert all(d.camera.hfov_deg == pytest.approx(70.0, abs=0.01) for d in site.drones)
    (kiosk,) = site.obstacles
    ox0, oy0, ox1, oy1 = kiosk.footprint
    assert ((ox0 + ox1) / 2, (oy0 + oy1) / 2) != ((x0 + x1) / 2, (y0 + y1) / 2)  # off centre
    # Every drone's home lies outside the plaza, looking in.
    assert all(not (x0 <= d.home_xy[0] <= x1 and y0 <= d.home_xy[1] <= y1) for d in site.drones)
    with pytest.raises(SiteError, match='references.source: simulate'):
        require_references(site)


def test_reference_image_of_another_size_than_the_camera_is_named(tmp_path, matrix_sample):
    refs = tmp_path / 'refs'
    refs.mkdir()
    for name in ('north', 'south'):  # real MATRIX reference files (1920 x 1080) for a site that says 640 x 480
        (refs / f'{name}.png').write_bytes((matrix_sample / 'reference/image_subsets/D1/0000.jpg').read_bytes())
        cal = matrix_sample / 'reference/calibrations'
        (refs / f'{name}_i.xml').write_bytes((cal / 'intrinsic/intr_Drone1_0000.xml').read_bytes())
        (refs / f'{name}_e.xml').write_bytes((cal / 'extrinsic/extr_Drone1_0000.xml').read_bytes())
    site = load_site(_write(tmp_path, _good()))
    with pytest.raises(
        SiteError,
        match=r': drones\[0\] \(north\)\.reference\.image: .*north\.png is 1920x1080, camera\.image_size is 640x480$',
    ):
        require_references(site)
    data = _good()
    for d in data['drones']:
        d['camera']['image_size'] = [1920, 1080]
    require_references(load_site(_write(tmp_path, data)))
    (refs / 'south_e.xml').write_text('<opencv_storage><rvec>1 2</rvec></opencv_storage>')
    with pytest.raises(SiteError, match=r': drones\[1\] \(south\)\.reference\.calibration: .*south_e\.xml'):
        require_references(load_site(_write(tmp_path, data)))
