"""Writer/reader round trip: MATRIX files written by MatrixWriter read back identical."""

import json

import numpy as np
import pytest

from matrix_core.datasets import DatasetError, MatrixDataset, MatrixWriter, open_dataset


def _copy_sample(src: MatrixDataset, dst, frames=(0, 1)):
    writer = MatrixWriter(dst, area=src.area, image_ext='.jpg')
    for frame in frames:
        for view in src.views:
            writer.write_image(view, frame, src.load_image(view, frame))
            writer.write_camera(view, frame, src.camera(view, frame))
            writer.write_line_of_sight(
                view,
                frame,
                {
                    pid: xyz
                    for pid, xyz in src.pedestrian_positions(frame).items()
                    if pid in src.line_of_sight(view, frame)
                },
            )
        writer.write_annotations(frame, src.annotations(frame), src.views)
        writer.write_pedestrians(frame, src.pedestrian_positions(frame))
    for view in src.views:
        writer.write_camera(view, 0, src.reference_camera(view), reference=True)
        writer.write_image(view, 0, src.load_image(view, 0), reference=True)
        pc = src.plane_correspondences(view, 1)
        writer.write_plane_points(view, 1, pc.marker_ids, pc.image_uv)
    writer.write_plane_markers(src.plane_markers)
    return open_dataset(dst)


@pytest.fixture(scope='module')
def pair(matrix_sample, tmp_path_factory):
    src = MatrixDataset(matrix_sample)
    return src, _copy_sample(src, tmp_path_factory.mktemp('roundtrip'))


def test_calibrations_identical(pair):
    src, dst = pair
    assert isinstance(dst, MatrixDataset) and dst.frames == (0, 1)
    for frame in dst.frames:
        for view in src.views:
            a, b = src.camera(view, frame), dst.camera(view, frame)
            np.testing.assert_allclose(b.K, a.K, rtol=0, atol=1e-9)
            np.testing.assert_allclose(b.cam_T_world, a.cam_T_world, rtol=0, atol=1e-12)
            np.testing.assert_allclose(b.dist, a.dist, rtol=0, atol=1e-15)
    for view in src.views:
        np.testing.assert_allclose(
            dst.reference_camera(view).cam_T_world, src.reference_camera(view).cam_T_world, atol=1e-12
        )


def test_annotation_files_byte_for_byte_equivalent(pair, matrix_sample):
    src, dst = pair
    for frame in dst.frames:
        original = json.loads((matrix_sample / f'annotations_positions/{frame:04d}.json').read_text())
        written = json.loads((dst.root / f'annotations_positions/{frame:04d}.json').read_text())
        assert written == original
        for a, b in zip(src.annotations(frame), dst.annotations(frame)):
            assert (a.person_id, a.position_id, a.boxes) == (b.person_id, b.position_id, b.boxes)
            np.testing.assert_array_equal(a.world_xy, b.world_xy)


def test_trajectories_los_and_planes(pair):
    src, dst = pair
    for frame in dst.frames:
        a, b = src.pedestrian_positions(frame), dst.pedestrian_positions(frame)
        assert a.keys() == b.keys()
        for pid in a:
            np.testing.assert_allclose(b[pid], a[pid], atol=1e-6)
        for view in src.views:
            assert dst.line_of_sight(view, frame) == src.line_of_sight(view, frame)
    # Our writer's frame-0 Planes files are valid; only the original generator's are bogus.
    assert dst.bogus_plane_frames == ()
    for view in src.views:
        a, b = src.plane_correspondences(view, 1), dst.plane_correspondences(view, 1)
        np.testing.assert_array_equal(a.marker_ids, b.marker_ids)
        np.testing.assert_allclose(b.image_uv, a.image_uv, atol=1e-6)
        np.testing.assert_allclose(b.world_xyz, a.world_xyz, atol=1e-6)
    assert dst.area == src.area


def test_malformed_folders_fail_clearly(tmp_path, matrix_sample):
    with pytest.raises(DatasetError, match='not a MATRIX, Wildtrack or MultiviewX'):
        open_dataset(tmp_path)
    (tmp_path / 'image_subsets' / 'D1').mkdir(parents=True)
    (tmp_path / 'calibrations' / 'intrinsic').mkdir(parents=True)
    with pytest.raises(DatasetError, match='missing calibrations/extrinsic'):
        open_dataset(tmp_path)
    (tmp_path / 'calibrations' / 'extrinsic').mkdir()
    (tmp_path / 'image_subsets' / 'D1' / '0000.png').write_bytes(b'not a png')
    (tmp_path / 'calibrations' / 'intrinsic' / 'intr_Drone1_0000.xml').write_text('<opencv_storage></opencv_storage>')
    ds = open_dataset(tmp_path)
    assert ds.frames == (0,)
    with pytest.raises(DatasetError):
        ds.camera('D1', 0)
