"""``evaluate`` on a copy of the real sample with one malformed annotation file: the run finishes, that frame
is left out of the image plane (its boxes cannot be scored) and counted with its reason in metrics.json and
the printed summary, and every output is written (it used to print the metrics, exit 2 and write no
metrics.json or pictures)."""

import json
import os
import shutil

import pytest

from matrix_core.cli.main import main
from matrix_core.fusion.settings import shipped_checkpoint

pytestmark = pytest.mark.slow


def test_one_malformed_annotation_file_is_reported_and_everything_written(matrix_sample, tmp_path, capsys):
    data = tmp_path / 'sample'
    shutil.copytree(matrix_sample, data, copy_function=os.symlink)
    (data / 'annotations_positions' / '0002.json').unlink()
    (data / 'annotations_positions' / '0002.json').write_text('{"bad')
    out = tmp_path / 'eval'
    code = main(
        ['evaluate', str(data), '--checkpoint', str(shipped_checkpoint()), '--out', str(out), '--heatmaps', '1']
    )
    printed = capsys.readouterr()
    assert code == 0, printed.err
    metrics = json.loads((out / 'metrics.json').read_text())
    failures = metrics['failures']
    assert failures['image_plane_frames_failed'] == 1 and failures['frames_scored'] == 5, failures
    (failed,) = failures['image_plane_failed_frames']
    assert failed['frame'] == 2 and 'malformed annotation file' in failed['reason'] and '0002.json' in failed['reason']
    assert 'image plane: frame 2 not scored: annotations: DatasetError: malformed annotation file' in printed.out
    assert metrics['image_plane']['all']['num_gt'] > 0 and metrics['detection']['recall'] > 0.8
    written = {p.name for p in out.iterdir()}
    assert {'metrics.json', 'tracks.txt', 'boxes_2d.txt', 'trajectories.png', 'heatmap_0000.png'} <= written
