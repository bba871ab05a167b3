"""Damaged and unfinished MCAP bags: a bag cut short, one whose records were overwritten in the
middle, one that is not MCAP at all, and one without metadata.yaml (its writer killed). Each yields its whole
frames before the damage, quickly, then a clear :class:`BagDamaged`; none hangs."""

import shutil
import struct
import time

import numpy as np
import pytest

from matrix_core.bags import BagDamaged, read_sequence_frames
from matrix_core.bags.salvage import connections, mcap_file
from matrix_core.cli.main import main

FRAMES = 4


@pytest.fixture(scope='module')
def sequence(tmp_path_factory):
    out = tmp_path_factory.mktemp('sim') / 'sim'
    assert (
        main(
            [
                'simulate',
                '--config',
                'simple',
                '--frames',
                str(FRAMES),
                '--seed',
                '1',
                '--width',
                '160',
                '--height',
                '90',
                '--out',
                str(out),
                '--bag',
                'true',
            ]
        )
        == 0
    )
    return out


def record_offsets(data: bytes) -> list:
    """(opcode, offset) of each top-level MCAP record (after the 8-byte magic); opcode 0x06 is a chunk (about
    1 MiB of messages: three frames here, the first chunk also holds the schemas and channels)."""
    out, at = [], 8
    while at + 9 <= len(data):
        opcode, length = data[at], struct.unpack_from('<Q', data, at + 1)[0]
        out.append((opcode, at))
        at += 9 + length
    return out


def damaged(sequence, tmp_path, mutate):
    bag = tmp_path / 'bag'
    shutil.copytree(sequence / 'bag', bag)
    f = mcap_file(bag)
    f.write_bytes(mutate(f.read_bytes()))
    return bag


def frames_then_error(bag):
    start, got = time.monotonic(), []
    with pytest.raises(BagDamaged) as err:
        for frame in read_sequence_frames(bag):
            got.append(frame)
    assert time.monotonic() - start < 10.0
    return got, str(err.value)


def _check_frames(got, sequence):
    whole = list(read_sequence_frames(sequence / 'bag'))
    assert len(whole) == FRAMES
    for a, b in zip(got, whole):
        assert a.stamp_ns == b.stamp_ns and set(a.images) == set(b.images) == {f'D{n}' for n in range(1, 9)}
        assert all(np.array_equal(a.images[v], b.images[v]) for v in a.images)


def test_a_bag_cut_short_gives_its_frames_before_the_cut(sequence, tmp_path):
    bag = damaged(sequence, tmp_path, lambda b: b[: [at for op, at in record_offsets(b) if op == 0x06][1] + 5000])
    got, message = frames_then_error(bag)
    assert 1 <= len(got) < FRAMES, len(got)
    _check_frames(got, sequence)
    assert 'cannot be opened as a whole bag' in message and 'messages before the damage' in message, message


def test_overwritten_records_in_the_middle(sequence, tmp_path):
    def overwrite_middle_chunk(b):
        at = [at for op, at in record_offsets(b) if op == 0x06][1] + 49  # the chunk's first message record
        return b[:at] + b'\xff' * 9 + b[at + 9 :]  # its opcode and length: garbage

    bag = damaged(sequence, tmp_path, overwrite_middle_chunk)
    got, message = frames_then_error(bag)
    assert 1 <= len(got) < FRAMES
    _check_frames(got, sequence)
    assert 'damaged after' in message or 'messages before the damage' in message, message


def test_not_an_mcap_file_and_no_bag_at_all(sequence, tmp_path):
    got, message = frames_then_error(damaged(sequence, tmp_path, lambda b: b'junk' * 100))
    assert got == [] and 'InvalidMagic' in message, message
    (tmp_path / 'empty').mkdir()
    got, message = frames_then_error(tmp_path / 'empty')
    assert got == [] and 'no single .mcap file' in message


def test_an_unfinished_bag_without_metadata_is_read_from_its_records(sequence, tmp_path):
    """What a killed writer leaves: no metadata.yaml, no summary; every chunk it had written is read."""
    bag = damaged(sequence, tmp_path, lambda b: b[: [at for op, at in record_offsets(b) if op == 0x06][-1]])
    (bag / 'metadata.yaml').unlink()
    got, message = frames_then_error(bag)
    assert len(got) >= 1
    _check_frames(got, sequence)
    assert connections(bag)['/D1/image_raw'] == 'sensor_msgs/msg/Image'


def test_matrix_tracker_bag_lists_what_a_damaged_bag_holds(sequence, tmp_path, capsys):
    bag = damaged(sequence, tmp_path, lambda b: b[: [at for op, at in record_offsets(b) if op == 0x06][1] + 5000])
    assert main(['bag', str(bag)]) == 1
    out, err = capsys.readouterr()
    assert '/D1/image_raw' in out and 'sensor_msgs/msg/Image' in out
    assert 'damaged bag:' in err and 'messages before the damage' in err
    assert main(['bag', str(sequence / 'bag')]) == 0
