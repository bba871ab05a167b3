"""System test: docs/your-own-site.md followed at a small size, from a recording to live tracks.

The plaza's boards description; a recording of the plaza (simulated, with its bag: what the user's drones
would record); `site init` from that bag; `train --site` on the site it wrote (a few frames, one epoch,
fine-tuning the tiny detector); `evaluate` of the recording offline with that checkpoint; and the recording's
bag replayed through the live graph (`run_graph`, the same processes as `ros2 launch`) with the site and the
checkpoint, then `evaluate-recording`. Each step must succeed and hand the next what it needs; the figures
of so short a training are not the point."""

import json
import subprocess

import pytest
import torch

from matrix_core.cli.main import main as cli
from matrix_core.evaluation.recording import read_recording_bag
from matrix_core.site import load_site

pytestmark = [pytest.mark.ros, pytest.mark.slow]
FRAMES = 4
# the boards description of the tutorial (docs/your-own-site.md, step 1)
BOARDS = """name: plaza
area: [-24.0, -12.0, 24.0, 12.0]
cell_m: 0.25
boards:
  - {name: west, origin: [-18.75, -8.75, 0.0], square: 0.25, inner_corners: [19, 19]}
  - {name: east, origin: [10.25, 3.25, 0.0], square: 0.25, inner_corners: [19, 19]}
  - {name: north, origin: [-2.1, 6.3, 0.0], square: 0.3, inner_corners: [15, 11]}
obstacles:
  - {name: kiosk, footprint: [6.0, -6.0, 10.0, -2.0], height: 4.0}
"""
# the site recipe at a test's size: small input, one epoch, no weight average
RECIPE = """base: site
bev: {image_width: 160, image_height: 96}
epochs: 1
average_epochs: 0
"""


def test_the_tutorial_from_a_recording_to_live_tracks(node_executable, tmp_path, capsys):
    boards, recipe = tmp_path / 'plaza_boards.yaml', tmp_path / 'recipe.yaml'
    boards.write_text(BOARDS)
    recipe.write_text(RECIPE)
    flight, site_dir, train = tmp_path / 'plaza_flight', tmp_path / 'plaza_site', tmp_path / 'train'

    # 2. the recording (here simulated, at the plaza's 1280 x 720) and 3. the site from it
    simulate = ['simulate', '--site', 'plaza', '--config', 'simple', '--frames', str(FRAMES), '--seed', '201']
    assert cli([*simulate, '--out', str(flight), '--bag', 'true']) == 0
    assert cli(['site', 'init', '--bag', str(flight / 'bag'), '--boards', str(boards), '--out', str(site_dir)]) == 0
    site = load_site(site_dir / 'site.yaml')
    assert site.drone_names == ('alpha', 'bravo', 'charlie', 'delta', 'echo'), capsys.readouterr().out
    assert cli(['site', 'check', str(site_dir / 'site.yaml'), '--require-references']) == 0

    # 4. train --site on the written site: its drones at their reference poses, seeds apart from the recording's
    argv = ['train', '--site', str(site_dir / 'site.yaml'), '--config', str(recipe), '--out', str(train)]
    argv += ['--init', 'detector_tiny_seed0.pt', '--sim-config', 'simple', '--train-seeds', '101', '--val-seeds']
    argv += ['111', '--frames', '3', '--val-frames', '2', '--image-scale', '0.25', '--device', 'cpu']
    capsys.readouterr()
    assert cli(argv) == 0
    printed = capsys.readouterr().out
    assert 'training seeds 101' in printed and 'validation seeds 111' in printed
    checkpoint = train / 'detector_plaza.pt'
    assert torch.load(checkpoint, weights_only=False)['site']['file'] == str(site_dir / 'site.yaml')

    # 5. offline: the recording scored with the new detector
    ev = tmp_path / 'plaza_eval'
    assert cli(['evaluate', str(flight), '--checkpoint', str(checkpoint), '--out', str(ev), '--device', 'cpu']) == 0
    metrics = json.loads((ev / 'metrics.json').read_text())
    assert metrics['views'] == list(site.drone_names) and metrics['failures']['frames_scored'] == FRAMES

    # 6. live: the recording's bag through the graph with the site and the checkpoint, then its score
    rec, logs = tmp_path / 'plaza_rec', tmp_path / 'logs'
    cmd = [str(node_executable('matrix_bringup', 'run_graph')), '--bag', str(flight / 'bag')]
    cmd += ['--site', str(site_dir / 'site.yaml'), '--checkpoint', str(checkpoint), '--record', str(rec)]
    cmd += ['--lockstep_timeout', '150', '--log_dir', str(logs)]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    said = run.stdout + run.stderr + '\n'.join(f'== {p.name}\n{p.read_text()[-3000:]}' for p in logs.glob('*.log'))
    assert run.returncode == 0, said
    recording = read_recording_bag(rec)
    assert len(set(recording.track_frames)) == FRAMES, said  # a TrackArray for every frame
    scored = subprocess.run(
        ['matrix-tracker', 'evaluate-recording', str(rec), '--ground-truth', str(flight / 'bag')],
        capture_output=True,
        text=True,
    )
    assert scored.returncode == 0 and 'MODA' in scored.stdout, scored.stdout + scored.stderr
