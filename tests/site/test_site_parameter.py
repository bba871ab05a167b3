"""The ``site`` setting: fields left at their MATRIX defaults follow the named site, given values win, the
MATRIX site changes nothing, and drones a site does not have are refused naming them."""

import argparse

import pytest

from matrix_bev_tracker.settings import FuseNodeSettings
from matrix_bringup.graph import GraphSettings
from matrix_calib.settings import CalibNodeSettings
from matrix_core.fusion.fuser import network_grid
from matrix_core.bev.settings import BevSettings
from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.site import SiteError, load_site, site_path
from matrix_core.site.parameter import check_bag_drones, follow_site, recorded_drones, site_following_fields
from matrix_register.settings import RegisterNodeSettings

PLAZA = load_site(site_path('plaza'))


def test_fields_left_at_the_matrix_defaults_take_the_sites_values():
    fuse = follow_site(FuseNodeSettings(site='plaza'))
    assert fuse.views == list(PLAZA.drone_names)
    assert fuse.area == list(PLAZA.area) and fuse.cell_m == PLAZA.cell_m
    assert fuse.obstacle_boxes == PLAZA.obstacle_boxes
    register = follow_site(RegisterNodeSettings(site='plaza'))
    assert register.area == list(PLAZA.area) and register.exclude_boxes == PLAZA.obstacle_boxes


def test_given_values_win_and_the_matrix_site_changes_nothing():
    assert follow_site(FuseNodeSettings(site='plaza', views=['bravo'])).views == ['bravo']
    for cls in (FuseNodeSettings, RegisterNodeSettings, CalibNodeSettings, GraphSettings):
        assert follow_site(cls(site='matrix')) == cls()
        assert follow_site(cls(site=str(site_path('matrix')))) == cls(site=str(site_path('matrix')))


def test_a_nodes_hosted_drones_are_another_setting_and_do_not_follow():
    # calib's and register's views name the drones of the process (empty: the namespace's), not the site's
    assert 'views' not in site_following_fields(CalibNodeSettings)
    assert follow_site(RegisterNodeSettings(site='plaza')).views == []


def test_cli_flags_follow_the_site():
    parser = argparse.ArgumentParser()
    add_settings_arguments(parser, FuseNodeSettings)
    assert settings_from_namespace(FuseNodeSettings, parser.parse_args(['--site', 'plaza'])).area == list(PLAZA.area)
    given = settings_from_namespace(
        FuseNodeSettings, parser.parse_args(['--site', 'plaza', '--area', '0', '0', '5', '5'])
    )
    assert given.area == [0.0, 0.0, 5.0, 5.0]


def test_a_launch_files_own_default_follows_the_site():
    # calib.launch.py hosts all of MATRIX's drones by default: with a site, all of the site's
    matrix_views = {'views': ['D1', 'D2', 'D3', 'D4', 'D5', 'D6', 'D7', 'D8']}
    calib = follow_site(CalibNodeSettings(site='plaza', views=matrix_views['views']), matrix_views)
    assert calib.views == list(PLAZA.drone_names)


def test_a_bad_site_is_an_error_naming_it(tmp_path):
    with pytest.raises(SiteError, match="site 'nowhere'.*site file not found.*shipped site: matrix, plaza"):
        follow_site(FuseNodeSettings(site='nowhere'))
    bad = tmp_path / 'yard.yaml'
    bad.write_text(site_path('plaza').read_text().replace('cell_m: 0.25', 'cell_m: 0.25\ncolour: red'))
    with pytest.raises(SiteError, match=r"yard.yaml: unknown key 'colour' \(allowed: "):
        follow_site(FuseNodeSettings(site=str(bad)))


def test_a_recording_of_drones_the_site_lacks_is_refused_naming_them():
    names = ['/D1/image_raw', '/D1/camera_info', '/D9/image/compressed', '/D9/ground_truth/camera_info', '/clock']
    assert recorded_drones(names) == ['D1', 'D9']
    with pytest.raises(SiteError, match=r'bag /data/run names drones D1, D9, which site plaza .* does not have'):
        check_bag_drones(PLAZA, names, '/data/run')
    check_bag_drones(PLAZA, ['/alpha/image_raw', '/echo/camera_info', '/tf'], '/data/run')


def test_the_grid_follows_the_area_and_refuses_another_cell_than_the_checkpoints():
    bev = BevSettings(cell_m=0.25)
    grid = network_grid(bev, FuseNodeSettings(site='plaza', area=list(PLAZA.area)))
    assert grid.shape == PLAZA.grid_shape(margin_m=bev.margin_m)
    with pytest.raises(ValueError, match=r'site yard: BEV cell 0.2 m, but checkpoint .* cells of 0.25 m'):
        network_grid(bev, FuseNodeSettings(site='yard', cell_m=0.2))
