"""A drone whose reference image cannot be read (``echo x > reference/image_subsets/D2/0000.jpg`` in a copy of
the real sample) is left out of the whole graph at start and named; the other drones and fuse run and are
tracked as well as a graph without that drone (the offline evaluation of the same views: live == offline)."""

import json
import os
import shutil
import subprocess

import pytest

from matrix_core.bags import write_sequence_bag
from matrix_core.cli.main import main as cli
from matrix_core.datasets import MatrixDataset
from matrix_core.datasets.drone_inputs import unreadable_drones

pytestmark = [pytest.mark.ros, pytest.mark.slow]
VIEWS = ['D1', 'D2', 'D5']


def broken_copy(sample, dst):
    """The sample as per-file links with D2's reference image replaced by two bytes of text."""
    shutil.copytree(sample, dst, copy_function=os.symlink)
    reference = dst / 'reference' / 'image_subsets' / 'D2' / '0000.jpg'
    reference.unlink()
    reference.write_text('x\n')
    return dst


def test_the_unreadable_drone_is_named(matrix_sample, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    problems = unreadable_drones(MatrixDataset(data), VIEWS)
    assert list(problems) == ['D2'] and 'cannot decode image' in problems['D2'] and '0000.jpg' in problems['D2']


def _run_graph(node_executable, bag, data, views, out):
    """run_graph on ``bag`` with ``data``'s reference: (completed process, node logs, live metrics)."""
    rec, logs = out / 'rec', out / 'logs'
    cmd = [str(node_executable('matrix_bringup', 'run_graph')), '--bag', str(bag), '--dataset', str(data)]
    cmd += ['--views', *views, '--record', str(rec), '--log_dir', str(logs), '--lockstep_timeout', '150']
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    node_logs = {p.name: p.read_text() for p in logs.glob('*.log')}
    live_json = out / 'live.json'
    scored = rec.exists() and cli(
        ['evaluate-recording', str(rec), '--ground-truth', str(bag), '--json', str(live_json)]
    )
    return run, node_logs, json.loads(live_json.read_text()) if scored == 0 else None


def test_run_graph_leaves_the_drone_out_and_tracks_the_others(matrix_sample, node_executable, tmp_path):
    data = broken_copy(matrix_sample, tmp_path / 'sample')
    bag = write_sequence_bag(MatrixDataset(matrix_sample), tmp_path / 'bag', compressed=True, progress=False)
    run, node_logs, live = _run_graph(node_executable, bag, data, VIEWS, tmp_path / 'broken')
    said = run.stdout + run.stderr
    assert run.returncode == 5, said + '\n'.join(f'== {k}\n{v[-3000:]}' for k, v in node_logs.items())
    assert 'D2 left out (reference: ' in said and 'ran without drone(s) D2' in said.splitlines()[-1], said
    assert sorted(node_logs) == ['D1_drone.log', 'D5_drone.log', 'bag_player.log', 'fuse.log', 'recorder.log']
    assert not any('Traceback' in text for text in node_logs.values())
    assert live['frames_without_tracks'] == []

    # the full graph with that view dropped, on the intact sample: the same tracking within 5 MODA points
    run, _, without = _run_graph(node_executable, bag, matrix_sample, ['D1', 'D5'], tmp_path / 'dropped')
    assert run.returncode == 0, run.stdout + run.stderr
    assert abs(live['detection']['moda'] - without['detection']['moda']) <= 0.05, (live, without)
    assert live['detection']['recall'] > 0.2  # two real views, the shipped checkpoint: people are found
