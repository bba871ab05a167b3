"""Wildtrack and MultiviewX readers, on small folders written here in each format's own encoding
(the real MultiviewX files are checked in test_multiviewx_sample.py)."""

import json

import cv2
import numpy as np
import pytest

from matrix_core.datasets import DatasetError, MultiviewXDataset, WildtrackDataset, open_dataset
from matrix_core.datasets.opencv_xml import write_matrices
from matrix_core.datasets.summary import summarize
from matrix_core.geometry.camera import Camera, pose_matrix

K = np.array([[1700.0, 0.0, 960.0], [0.0, 1700.0, 540.0], [0.0, 0.0, 1.0]])
MIRROR_Y = np.diag([1.0, -1.0, 1.0])


def _file_extrinsics(cam: Camera, fmt) -> tuple:
    """(rvec, tvec) as the format's own files state them, from an internal camera.

    MultiviewX (measured on its real files): left-handed world (file y = -internal y) and a camera frame
    looking down -z, i.e. ``R_file = -R MIRROR_Y``, ``t_file = -t``; Wildtrack: as is, ``tvec`` in cm.
    """
    R, t = cam.R, cam.t
    if fmt.left_handed:
        R, t = -R @ MIRROR_Y, -t
    return cv2.Rodrigues(R)[0].reshape(3), t / fmt.metres_per_unit


def _look_at(eye, target):
    """cam_T_world of a camera at ``eye`` looking at ``target`` (z up, no roll)."""
    z = np.asarray(target, float) - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z])
    return pose_matrix(R, -R @ eye)


def _write_rig(root, fmt_cls, eyes, target, unit, text_extrinsics, frame_ids, person_world):
    fmt = fmt_cls.FORMAT
    cams = [Camera(K, _look_at(np.array(e), target), 1920, 1080) for e in eyes]
    for i, (cam, stem) in enumerate(zip(cams, fmt.camera_files)):
        write_matrices(
            root / 'calibrations' / fmt.intrinsic_dir / f'intr_{stem}.xml',
            {'camera_matrix': K, 'distortion_coefficients': np.zeros((1, 5))},
        )
        extr = root / 'calibrations' / 'extrinsic' / f'extr_{stem}.xml'
        rvec, tvec = _file_extrinsics(cam, fmt)
        assert fmt.metres_per_unit == unit
        if text_extrinsics:  # Wildtrack writes rvec/tvec as plain text nodes
            extr.parent.mkdir(parents=True, exist_ok=True)
            extr.write_text(
                '<?xml version="1.0"?>\n<opencv_storage>\n'
                f'<rvec>{" ".join(repr(float(v)) for v in rvec)}</rvec>\n'
                f'<tvec>{" ".join(repr(float(v)) for v in tvec)}</tvec>\n</opencv_storage>\n'
            )
        else:
            write_matrices(extr, {'rvec': rvec.reshape(3, 1), 'tvec': tvec.reshape(3, 1)})
        for f in frame_ids:
            img_dir = root / 'Image_subsets' / f'C{i + 1}'
            img_dir.mkdir(parents=True, exist_ok=True)
            cv2.imwrite(str(img_dir / f'{f:0{fmt.frame_digits}d}.png'), np.zeros((1080, 1920, 3), np.uint8))
    ds = fmt_cls(root)
    pid = ds.world_to_position(person_world)
    views = []
    for i, cam in enumerate(cams):
        u, v = cam.project([[*person_world, 0.0]])[0]
        views.append({'viewNum': i, 'xmin': int(u) - 20, 'ymin': int(v) - 150, 'xmax': int(u) + 20, 'ymax': int(v)})
    views.append({'viewNum': len(cams), 'xmin': -1, 'ymin': -1, 'xmax': -1, 'ymax': -1})
    ann = root / 'annotations_positions'
    ann.mkdir()
    for f in frame_ids:
        (ann / f'{f:0{fmt.annotation_digits}d}.json').write_text(
            json.dumps([{'personID': 7, 'positionID': pid, 'views': views}])
        )
    return cams, pid


@pytest.mark.parametrize(
    'fmt_cls, unit, text, target, person',
    [
        (WildtrackDataset, 0.01, True, (3.0, 9.0, 0.0), (2.0, 10.0)),
        (MultiviewXDataset, 1.0, False, (12.5, -8.0, 0.0), (12.0, -7.5)),  # internal y = -file y
    ],
)
def test_reader_roundtrip(tmp_path, fmt_cls, unit, text, target, person):
    n = len(fmt_cls.FORMAT.camera_files)
    eyes = [
        (target[0] + 12 * np.cos(a), target[1] + 12 * np.sin(a), 6.0)
        for a in np.linspace(0, 2 * np.pi, n, endpoint=False)
    ]
    cams, pid = _write_rig(tmp_path, fmt_cls, eyes, target, unit, text, [0, 5], person)
    ds = open_dataset(tmp_path)
    assert type(ds) is fmt_cls
    assert ds.views == tuple(f'C{i + 1}' for i in range(n)) and ds.frames == (0, 5)
    for view, cam in zip(ds.views, cams):
        np.testing.assert_allclose(ds.camera(view, 5).cam_T_world, cam.cam_T_world, atol=1e-9)
    # positionID -> world is the grid corner within one cell of the true position
    (person_ann,) = ds.annotations(5)
    assert person_ann.person_id == 7 and person_ann.position_id == pid
    assert np.all(np.abs(person_ann.world_xy - person) <= ds.FORMAT.grid_cell_m)
    assert set(person_ann.boxes) == set(ds.views)  # the extra invisible view entry is ignored
    # the box bottom maps back to the person through the ground homography
    for view in ds.views:
        g = ds.camera(view, 5).backproject_to_ground(person_ann.boxes[view].bottom_center[None])[0]
        assert np.linalg.norm(g[:2] - person) < 0.05
    info = summarize(ds)
    assert info['format'] == fmt_cls.format_name and info['people'] == 1 and info['frames'] == 2


def test_wildtrack_grid_convention(tmp_path):
    for sub in ('Image_subsets', 'calibrations/intrinsic_zero', 'calibrations/extrinsic'):
        (tmp_path / sub).mkdir(parents=True)
    ds = WildtrackDataset(tmp_path)
    fmt = ds.FORMAT
    # Wildtrack: x = -3 m + 0.025 * (pos % 480), y = -9 m + 0.025 * (pos // 480)
    origin = np.array(fmt.grid_origin_m)
    assert tuple(origin) == (-3.0, -9.0)
    pos = 123 + 480 * 456
    expected = origin + 0.025 * np.array([123, 456])
    np.testing.assert_allclose(ds.position_to_world(pos), expected)
    assert ds.world_to_position(expected + 0.01) == pos
    assert ds.area == (-3.0, -9.0, 9.0, 27.0)


def test_missing_calibration_is_a_clear_error(tmp_path):
    (tmp_path / 'Image_subsets' / 'C1').mkdir(parents=True)
    (tmp_path / 'calibrations' / 'intrinsic').mkdir(parents=True)
    (tmp_path / 'calibrations' / 'extrinsic').mkdir(parents=True)
    cv2.imwrite(str(tmp_path / 'Image_subsets' / 'C1' / '0000.png'), np.zeros((10, 10, 3), np.uint8))
    ds = open_dataset(tmp_path)
    assert isinstance(ds, MultiviewXDataset)
    with pytest.raises(DatasetError, match='intr_Camera1.xml'):
        ds.camera('C1', 0)


def test_multiviewx_grid_convention(tmp_path):
    for sub in ('Image_subsets', 'calibrations/intrinsic', 'calibrations/extrinsic'):
        (tmp_path / sub).mkdir(parents=True)
    ds = MultiviewXDataset(tmp_path)
    # MultiviewX: file x = (pos % 1000) / 40, y = (pos // 1000) / 40 metres on a 25 m x 16 m area; its world
    # is left-handed, so the internal (right-handed) y is the file's negated.
    pos = 123 + 1000 * 456
    expected = np.array([123 / 40, -456 / 40])
    np.testing.assert_allclose(ds.position_to_world(pos), expected)
    assert ds.world_to_position(expected + [0.01, -0.01]) == pos
    assert ds.area == (0.0, -16.0, 25.0, 0.0)


def test_wildtrack_reader_matches_a_folder_written_from_the_published_conventions(tmp_path):
    # Written without the reader: Wildtrack's README and loaders state positionID = gx + 480 gy on 2.5 cm
    # cells from (-300, -900) cm (480 x 1440), calibrations/intrinsic_zero/intr_<cam>.xml (camera_matrix,
    # zero distortion_coefficients) and calibrations/extrinsic/extr_<cam>.xml with <rvec>/<tvec> text nodes,
    # world in centimetres; a person's box stands on raw cv2.projectPoints of its position.
    stems = WildtrackDataset.FORMAT.camera_files
    rng = np.random.default_rng(4)
    grid = np.c_[rng.integers(40, 440, 30), rng.integers(100, 1300, 30)]
    pos_ids = grid[:, 0] + 480 * grid[:, 1]
    feet_cm = np.c_[np.array([-300.0, -900.0]) + 2.5 * grid, np.zeros(len(grid))]
    centre_cm = np.array([300.0, 900.0, 0.0])
    persons = [{'personID': i, 'positionID': int(p), 'views': []} for i, p in enumerate(pos_ids)]
    for i, stem in enumerate(stems):
        a = 2 * np.pi * i / len(stems)
        eye = centre_cm + [900 * np.cos(a), 2000 * np.sin(a), 600.0]
        cam_T_world = _look_at(eye, centre_cm)
        rvec, tvec = cv2.Rodrigues(cam_T_world[:3, :3])[0].reshape(3), cam_T_world[:3, 3]
        write_matrices(
            tmp_path / 'calibrations' / 'intrinsic_zero' / f'intr_{stem}.xml',
            {'camera_matrix': K, 'distortion_coefficients': np.zeros((1, 5))},
        )
        (tmp_path / 'calibrations' / 'extrinsic' / f'extr_{stem}.xml').parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / 'calibrations' / 'extrinsic' / f'extr_{stem}.xml').write_text(
            '<?xml version="1.0"?>\n<opencv_storage>\n'
            f'<rvec>{" ".join(f"{v:.12e}" for v in rvec)}</rvec>\n'
            f'<tvec>{" ".join(f"{v:.12e}" for v in tvec)}</tvec>\n</opencv_storage>\n'
        )
        (tmp_path / 'Image_subsets' / f'C{i + 1}').mkdir(parents=True)
        cv2.imwrite(str(tmp_path / 'Image_subsets' / f'C{i + 1}' / '00000000.png'), np.zeros((1080, 1920, 3), np.uint8))
        uv = cv2.projectPoints(feet_cm.reshape(-1, 1, 3), rvec, tvec, K, np.zeros(5))[0].reshape(-1, 2)
        depth = (feet_cm - eye) @ cam_T_world[2, :3]
        for person, (u, v), d in zip(persons, uv, depth):
            seen = d > 0 and 20 <= u < 1900 and 150 <= v < 1080
            box = (int(round(u)) - 20, int(round(v)) - 150, int(round(u)) + 20, int(round(v))) if seen else (-1,) * 4
            person['views'].append(dict(zip(('xmin', 'ymin', 'xmax', 'ymax'), box), viewNum=i))
    (tmp_path / 'annotations_positions').mkdir()
    (tmp_path / 'annotations_positions' / '00000000.json').write_text(json.dumps(persons))

    ds = open_dataset(tmp_path)
    assert isinstance(ds, WildtrackDataset) and ds.area == (-3.0, -9.0, 9.0, 27.0)
    annotated = ds.annotations(0)
    np.testing.assert_allclose([p.world_xy for p in annotated], feet_cm[:, :2] / 100.0, atol=1e-12)
    for view in ds.views:
        cam = ds.camera(view, 0)
        seen = [p for p in annotated if view in p.boxes]
        assert len(seen) >= 5
        foot = cam.project(np.c_[[p.world_xy for p in seen], np.zeros(len(seen))])
        error = np.linalg.norm(foot - [p.boxes[view].bottom_center for p in seen], axis=1)
        assert np.max(error) <= 0.71, f'{view}: foot points {np.max(error):.2f} px from the boxes'
        assert 5.5 < cam.center[2] < 6.5  # 600 cm up
