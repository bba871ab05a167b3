"""Obstacles and flat-ground extent come from the dataset when it states them (simulated folders)."""

from matrix_core.datasets import MatrixDataset
from matrix_core.register.scene import FACADE_CLEARANCE_M, scene_from_meta, settings_for_dataset
from matrix_core.register.settings import MATRIX_BLOCK, RegisterSettings
from matrix_core.sim.config import load_scene_config, scene_config_to_dict


def _meta(variant):
    return {'simulator': {'config': scene_config_to_dict(load_scene_config(variant))}}


def test_the_real_sample_keeps_the_configured_scene(matrix_sample):
    settings = RegisterSettings()
    same, note = settings_for_dataset(settings, MatrixDataset(matrix_sample))
    assert same is settings and note == '' and same.exclude_boxes == MATRIX_BLOCK


def test_simulated_scene_configs_give_their_block_pillars_and_ground_extent():
    boxes, margin = scene_from_meta(_meta('simple'))
    assert boxes == [] and margin == 26.0 - FACADE_CLEARANCE_M - 7.5  # no block, ground up to the buildings
    boxes, margin = scene_from_meta(_meta('complex'))
    assert boxes[:5] == [12.5, -17.5, 17.5, -12.5, 10.0] and len(boxes) == 15  # block + 2 pillars
    assert margin == 34.0 - FACADE_CLEARANCE_M - 15.0
    assert scene_from_meta({}) is None and scene_from_meta({'simulator': {}}) is None


def test_the_dataset_scene_can_be_switched_off(tmp_path):
    class Folder:  # anything with a meta dict, like MatrixDataset
        meta, root = _meta('simple'), tmp_path

    taken, note = settings_for_dataset(RegisterSettings(), Folder())
    assert taken.exclude_boxes == [] and taken.ground_margin_m > 10 and '0 obstacle box(es)' in note
    kept, note = settings_for_dataset(RegisterSettings(scene_from_dataset=False), Folder())
    assert kept.exclude_boxes == MATRIX_BLOCK and kept.ground_margin_m == 0.0 and note == ''
