"""A calibration scene YAML with a mistyped key is an error naming it and the allowed keys."""

import pytest
import yaml

from matrix_core.calib.scene import default_config_path, load_scene


def test_mistyped_keys_are_named(tmp_path):
    scene = yaml.safe_load(default_config_path('sim_complex.yaml').read_text())  # boards and intrinsics spelt out
    scene['intrinsic'] = scene.pop('intrinsics')  # top level
    path = tmp_path / 'scene.yaml'
    path.write_text(yaml.safe_dump(scene))
    with pytest.raises(ValueError, match=r"unknown keys \['intrinsic'\] \(allowed: .*'intrinsics'"):
        load_scene(path)
    scene['intrinsics'] = scene.pop('intrinsic')
    scene['boards'][0]['colums'] = 3  # inside a board
    path.write_text(yaml.safe_dump(scene))
    with pytest.raises(ValueError, match=r"unknown keys \['colums'\]"):
        load_scene(path)


def test_a_scene_naming_a_site_takes_its_boards_and_camera(tmp_path):
    scene = load_scene()  # the real sample's: site: matrix
    site = yaml.safe_load(default_config_path().read_text())
    assert site == {'site': 'matrix'}
    assert [b.name for b in scene.boards] == ['A', 'B'] and scene.image_size == (1920, 1080)
    path = tmp_path / 'scene.yaml'
    path.write_text(yaml.safe_dump({'site': 'matrix', 'boards': []}))
    with pytest.raises(ValueError, match=r'boards come from the site matrix; give them in one place'):
        load_scene(path)
    path.write_text(yaml.safe_dump({'site': 'plaza'}))
    assert [b.name for b in load_scene(path).boards] == ['west', 'east', 'north']
    assert load_scene(path).image_size == (1280, 720)
    path.write_text(yaml.safe_dump({'site': 'nowhere.yaml'}))
    with pytest.raises(FileNotFoundError, match='site file not found: nowhere.yaml'):
        load_scene(path)
