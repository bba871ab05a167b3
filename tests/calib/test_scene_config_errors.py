"""A calibration scene YAML with a mistyped key is an error naming it and the allowed keys."""

import pytest
import yaml

from matrix_core.calib.scene import default_config_path, load_scene


def test_mistyped_keys_are_named(tmp_path):
    scene = yaml.safe_load(default_config_path().read_text())
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
