"""``matrix-tracker simulate``: a frame that raises is left out whole and the sequence goes on; what was
written stays readable, and ``simulate_summary.json`` says which frame failed and why.

"Nothing written is lost" for the simulator: every frame written before (and after) the failing one stays
in the folder and the bag, the bag is closed properly, and no half-written frame is left for a reader to take
for a whole one."""

import json

import numpy as np
import pytest

from matrix_core.bags import read_sequence_frames
from matrix_core.cli.main import main
from matrix_core.datasets import MatrixWriter, open_dataset
from matrix_core.sim import sequence


def test_a_failing_frame_is_left_out_and_the_others_are_kept(tmp_path, monkeypatch, capsys):
    write_annotations = MatrixWriter.write_annotations

    def failing(self, frame, *args):  # after every image and calibration of the frame was written
        if frame == 2:
            raise OSError('injected: disk hiccup')
        return write_annotations(self, frame, *args)

    monkeypatch.setattr(MatrixWriter, 'write_annotations', failing)
    out = tmp_path / 'sim'
    assert (
        main(
            [
                'simulate',
                '--config',
                'simple',
                '--frames',
                '4',
                '--seed',
                '3',
                '--out',
                str(out),
                '--width',
                '160',
                '--height',
                '90',
                '--bag',
                'true',
            ]
        )
        == 0
    )
    assert 'wrote 3 of 4 frames of simple' in capsys.readouterr().out
    summary = json.loads((out / sequence.SUMMARY_FILE).read_text())
    assert summary['frames_written'] == 3 and summary['stopped'] == '' and summary['last_frame_written'] == 3
    assert summary['failed_frames'] == [{'frame': 2, 'reason': 'OSError: injected: disk hiccup'}]
    left = [p for p in out.rglob('*0002*') if p.is_file() and 'reference' not in p.parts]
    assert left == []  # no half-written frame
    ds = open_dataset(out)
    assert ds.frames == (0, 1, 3) and ds.incomplete_frames == {}
    assert all(ds.annotations(f) for f in (0, 1, 3))
    frames = list(read_sequence_frames(out / 'bag'))  # the bag was closed and holds the whole frames
    assert [f.stamp_ns for f in frames] == [1_000_000_000, 1_500_000_000, 2_500_000_000]
    assert np.array_equal(frames[2].images['D1'], ds.load_image('D1', 3))


def test_an_interrupted_run_keeps_what_it_wrote(tmp_path, monkeypatch):
    """Ctrl-C (or any error that is not one frame's) in the middle: the bag is closed, the summary says so."""
    write_frame = sequence.write_frame

    def interrupted(sim, writer, frame, out):
        if frame == 2:
            raise KeyboardInterrupt
        return write_frame(sim, writer, frame, out)

    monkeypatch.setattr(sequence, 'write_frame', interrupted)
    out = tmp_path / 'sim'
    with pytest.raises(KeyboardInterrupt):
        main(
            [
                'simulate',
                '--config',
                'simple',
                '--frames',
                '4',
                '--seed',
                '3',
                '--out',
                str(out),
                '--width',
                '160',
                '--height',
                '90',
                '--bag',
                'true',
            ]
        )
    summary = json.loads((out / sequence.SUMMARY_FILE).read_text())
    assert (summary['stopped'], summary['frames_written'], summary['last_frame_written']) == ('interrupted', 2, 1)
    assert open_dataset(out).frames == (0, 1)
    assert len(list(read_sequence_frames(out / 'bag'))) == 2
