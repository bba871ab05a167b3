"""End-to-end: `matrix-tracker simulate` output is deterministic, readable by the MATRIX reader and the
bag opens with rosbags and mcap."""

import json

import numpy as np
import pytest
from mcap.reader import make_reader

from matrix_core.bags import bag_topics, read_bag, read_sequence_frames
from matrix_core.cli.main import main
from matrix_core.datasets import open_dataset


def _simulate(out, seed, config='simple', frames=3, extra=()):
    argv = [
        'simulate',
        '--config',
        config,
        '--frames',
        str(frames),
        '--seed',
        str(seed),
        '--out',
        str(out),
        '--fast',
        'true',
        *extra,
    ]
    assert main(argv) == 0
    return out


@pytest.fixture(scope='module')
def complex_run(tmp_path_factory):
    return _simulate(tmp_path_factory.mktemp('sim') / 'complex', 7, 'complex', 3, ('--bag', 'true'))


def test_same_seed_gives_byte_identical_annotations(tmp_path):
    a, b, c = (_simulate(tmp_path / n, s) for n, s in (('a', 11), ('b', 11), ('c', 12)))
    for frame in range(3):
        name = f'annotations_positions/{frame:04d}.json'
        assert (a / name).read_bytes() == (b / name).read_bytes()
        assert (a / f'matchings/Pedestrians/3d_{frame:04d}.txt').read_bytes() == (
            b / f'matchings/Pedestrians/3d_{frame:04d}.txt'
        ).read_bytes()
    last = 'annotations_positions/0002.json'
    assert (a / last).read_bytes() != (c / last).read_bytes()


def test_matrix_reader_reads_simulated_sequence(complex_run):
    ds = open_dataset(complex_run)
    assert ds.views == tuple(f'D{k}' for k in range(1, 9)) and ds.frames == (0, 1, 2)
    assert ds.area == (0.0, -30.0, 30.0, 0.0) and ds.has_reference
    truth = json.loads((complex_run / 'sim_ground_truth/0001.json').read_text())
    for view in ds.views:
        cam = ds.camera(view, 1)
        H = np.array(truth[view]['img_H_ground'])
        assert np.allclose(cam.img_H_ground() / cam.img_H_ground()[2, 2], H, atol=1e-6)
        assert np.allclose(cam.center, truth[view]['camera_center'], atol=1e-6)
        assert 10.0 <= cam.tilt_deg <= 50.0 and 11.0 <= cam.center[2] <= 13.5
        pc = ds.plane_correspondences(view, 1)
        if pc is not None and len(pc.marker_ids):
            assert np.abs(cam.project(pc.world_xyz) - pc.image_uv).max() < 1e-3
    persons = ds.annotations(1)
    positions = ds.pedestrian_positions(1)
    assert len(persons) == 40 and set(positions) == set(range(40))
    views_per_person = [len(p.boxes) for p in persons]
    assert 4.0 <= np.mean(views_per_person) <= 8.0
    for p in persons:
        assert np.linalg.norm(p.world_xy - positions[p.person_id][:2]) < 0.15  # positionID cell
        assert set(p.boxes) == {v for v in ds.views if p.person_id in ds.line_of_sight(v, 1)}
        for view, box in p.boxes.items():
            foot = ds.camera(view, 1).project(positions[p.person_id][None])[0]
            assert abs(box.ymax - foot[1]) <= 1.0 and box.xmin - 1 <= foot[0] <= box.xmax + 1


def test_bag_opens_with_rosbags_and_mcap(complex_run):
    bag = complex_run / 'bag'
    topics = bag_topics(bag)
    assert topics['/D1/image_raw'] == ('sensor_msgs/msg/Image', 3)
    assert topics['/D8/ground_truth/camera_info'] == ('sensor_msgs/msg/CameraInfo', 3)
    assert topics['/ground_truth/pedestrians'] == ('geometry_msgs/msg/PoseArray', 3)
    ds = open_dataset(complex_run)
    frames = list(read_sequence_frames(bag))
    assert [f.stamp_ns for f in frames] == [1_000_000_000, 1_500_000_000, 2_000_000_000]
    for frame_index, f in enumerate(frames):
        assert set(f.images) == set(ds.views) == set(f.cameras)
        assert np.array_equal(f.images['D3'], ds.load_image('D3', frame_index))
        assert np.allclose(f.cameras['D3'].P, ds.camera('D3', frame_index).P, atol=1e-6)
        truth = ds.pedestrian_positions(frame_index)
        assert set(f.positions) == set(truth)
        assert max(np.abs(f.positions[i] - truth[i]).max() for i in truth) < 1e-5
    frame_ids = {m.msg.header.frame_id for m in read_bag(bag, ['/D2/image_raw', '/ground_truth/pedestrians'])}
    assert frame_ids == {'D2/camera_optical', 'world'}
    with open(next(bag.glob('*.mcap')), 'rb') as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert summary.statistics.message_count == sum(n for _, n in topics.values())
        assert {c.topic for c in summary.channels.values()} == set(topics)


@pytest.mark.slow
def test_real_sample_converts_to_a_compressed_bag(matrix_sample, tmp_path):
    """The bag writer takes any MATRIX folder: the real sample round-trips through a JPEG bag."""
    from matrix_core.bags import write_sequence_bag

    real = open_dataset(matrix_sample)
    bag = write_sequence_bag(real, tmp_path / 'real_bag', compressed=True, progress=False)
    assert bag_topics(bag)['/D5/image/compressed'] == ('sensor_msgs/msg/CompressedImage', len(real.frames))
    frames = list(read_sequence_frames(bag))
    assert len(frames) == len(real.frames)
    last = frames[-1]
    frame = real.frames[-1]
    cam = real.camera('D5', frame)
    assert np.allclose(last.cameras['D5'].P, cam.P, atol=1e-6)
    diff = np.abs(last.images['D5'].astype(int) - real.load_image('D5', frame).astype(int))
    assert diff.mean() < 3.0  # JPEG q95 of a JPEG
    assert set(last.positions) == set(real.pedestrian_positions(frame))
