"""The sequence clock: written into the bag's metadata by the writer, read back by the reader and by the
recording evaluation (the CLI flags only override it); bags written before it was stored get the default
clock with a logged note."""

import json
import logging
import math

import numpy as np
import pytest
import yaml

from matrix_core.bags import SequenceBagWriter, SequenceClock, read_bag, read_sequence_clock
from matrix_core import topics as t
from matrix_core.bags.clock import DEFAULT_CLOCK, stored_sequence_clock
from matrix_core.message_fields import stamp_ns
from matrix_core.cli.main import main as cli
from matrix_core.evaluation.recording import ground_truth_from_bag
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.metrics import write_bev_points

CLOCK = SequenceClock(start_time=2.0, frame_period=0.25)


def test_clock_numbers_frames_both_ways():
    assert (DEFAULT_CLOCK.start_time, DEFAULT_CLOCK.frame_period) == (1.0, 0.5)
    assert [CLOCK.stamp(i) for i in range(3)] == [2.0, 2.25, 2.5]
    assert CLOCK.stamp_ns(3) == 2_750_000_000
    assert [CLOCK.frame(CLOCK.stamp(i) + 1e-7) for i in range(5)] == list(range(5))
    assert CLOCK.frame_ns(CLOCK.stamp_ns(7)) == 7
    for bad in ((1.0, 0.0), (1.0, -0.5), (math.nan, 0.5), (1.0, math.inf)):
        with pytest.raises(ValueError):
            SequenceClock(*bad)


def test_overrides_replace_only_given_values():
    assert CLOCK.overridden() == CLOCK
    assert CLOCK.overridden(start_time=math.nan, frame_period=0.5) == SequenceClock(2.0, 0.5)
    assert CLOCK.overridden(start_time=0.0) == SequenceClock(0.0, 0.25)
    with pytest.raises(ValueError):
        CLOCK.overridden(frame_period=0.0)


def _write_bag(path, clock=None, frames=3):
    camera = Camera(np.array([[10.0, 0, 4], [0, 10.0, 4], [0, 0, 1]]), pose_matrix(np.eye(3), [0, 0, 5.0]), 8, 8)
    with SequenceBagWriter(path, ['D1'], clock=clock) as bag:
        for i in range(frames):
            bag.write_frame(
                i,
                {'D1': np.zeros((8, 8, 3), np.uint8)},
                {'D1': camera},
                {7: np.array([1.0 + i, -2.0, 0.0]), 9: np.array([5.0, -6.0 - i, 0.0])},
            )
    return path


def test_writer_stores_the_clock_and_stamps_with_it(tmp_path):
    bag = _write_bag(tmp_path / 'bag', CLOCK)
    custom = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']['custom_data']
    assert custom == {'matrix_tracker.start_time': '2.0', 'matrix_tracker.frame_period': '0.25'}
    assert read_sequence_clock(bag) == CLOCK
    stamps = [stamp_ns(m.msg.header) for m in read_bag(bag, [t.PEDESTRIANS_TOPIC])]
    assert stamps == [CLOCK.stamp_ns(i) for i in range(3)]
    gt = ground_truth_from_bag(bag)  # frames by the stored clock, no timing given
    assert sorted(set(gt.frames.tolist())) == [0, 1, 2] and len(gt) == 6


def test_default_clock_is_stored_too(tmp_path):
    assert stored_sequence_clock(_write_bag(tmp_path / 'bag', frames=1)) == DEFAULT_CLOCK


def test_bag_without_a_clock_gets_the_default_with_a_note(tmp_path, caplog):
    bag = _write_bag(tmp_path / 'old', CLOCK)
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())
    del meta['rosbag2_bagfile_information']['custom_data']  # as written before the clock was stored
    (bag / 'metadata.yaml').write_text(yaml.safe_dump(meta))
    assert stored_sequence_clock(bag) is None
    with caplog.at_level(logging.WARNING, logger='matrix_core.bags.clock'):
        assert read_sequence_clock(bag) == DEFAULT_CLOCK
    assert 'stores no sequence clock' in caplog.text
    notes = []
    assert read_sequence_clock(bag, note=notes.append) == DEFAULT_CLOCK and len(notes) == 1
    with pytest.raises(FileNotFoundError):
        read_sequence_clock(tmp_path / 'nothing')


def test_evaluate_recording_takes_the_clock_from_the_sequence_bag(tmp_path):
    bag = _write_bag(tmp_path / 'bag', CLOCK)
    write_bev_points(tmp_path / 'tracks.txt', ground_truth_from_bag(bag))
    out = tmp_path / 'm.json'
    assert (
        cli(['evaluate-recording', str(tmp_path / 'tracks.txt'), '--ground-truth', str(bag), '--json', str(out)]) == 0
    )
    assert json.loads(out.read_text())['tracking']['mota'] == 1.0
    # an override shifts the ground truth by one frame: nothing matches any more
    assert (
        cli(
            [
                'evaluate-recording',
                str(tmp_path / 'tracks.txt'),
                '--ground-truth',
                str(bag),
                '--start-time',
                '1.75',
                '--json',
                str(out),
                '--overwrite',
            ]
        )
        == 0
    )
    assert json.loads(out.read_text())['detection']['recall'] == 0.0
    assert (
        cli(['evaluate-recording', str(tmp_path / 'tracks.txt'), '--ground-truth', str(bag), '--frame-period', '0'])
        == 2
    )
