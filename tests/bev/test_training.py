"""A few training steps on the real sample reduce the loss; checkpoints resume; evaluate writes PNGs."""

import json

import numpy as np
import pytest
import torch

from matrix_core.bev.config import SequenceSpec, TrainConfig, load_config
from matrix_core.bev.data import BevFrames
from matrix_core.bev.registry import build_model
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.training import seed_everything, training_step
from matrix_core.cli.main import main

SETTINGS = BevSettings(model='bev_tiny', image_width=160, image_height=96, cell_m=0.5)


@pytest.mark.slow
def test_training_steps_reduce_the_loss(matrix_sample):
    torch.set_num_threads(1)
    seed_everything(0)
    data = BevFrames(matrix_sample, SETTINGS, frames=[1, 2])
    config = TrainConfig(train=[SequenceSpec(str(matrix_sample))], bev=SETTINGS, view_dropout=0.0)
    model = build_model('bev_tiny')
    opt = torch.optim.AdamW(model.parameters(), lr=3e-3)
    rng = np.random.default_rng(0)

    def loss_now():
        model.train()     # batch statistics: after 12 steps the running ones are not settled yet
        with torch.no_grad():
            return float(training_step(model, [data], [(0, 1)], config, rng)['total'])

    before = loss_now()
    model.train()
    for _ in range(12):
        terms = training_step(model, [data], [(0, 1)], config, rng)
        opt.zero_grad()
        terms['total'].backward()
        opt.step()
    after = loss_now()
    print(f"loss before {before:.3f} after {after:.3f}")
    assert after < 0.8 * before, (before, after)


@pytest.mark.slow
def test_train_resume_and_evaluate_cli(matrix_sample, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv('MATRIX_SHARED', str(matrix_sample.parent))
    cfg = tmp_path / 'tiny.yaml'
    cfg.write_text(f"""
train:
  - path: $MATRIX_SHARED/{matrix_sample.name}
    frames: [0, 2]
val:
  - path: $MATRIX_SHARED/{matrix_sample.name}
    frames: [3, 4]
bev: {{model: bev_tiny, image_width: 160, image_height: 96, cell_m: 0.5}}
epochs: 1
seed: 3
""")
    out = tmp_path / 'run'
    assert main(['train', '--config', str(cfg), '--out', str(out)]) == 0
    assert main(['train', '--config', str(cfg), '--out', str(out), '--resume', '--epochs', '2']) == 0
    history = json.loads((out / 'history.json').read_text())
    assert [h['epoch'] for h in history] == [1, 2] and 'val_moda' in history[-1]
    assert (out / 'best.pt').is_file() and (out / 'last.pt').is_file()
    capsys.readouterr()
    ev = tmp_path / 'eval'
    assert main(['evaluate', str(matrix_sample), '--checkpoint', str(out / 'last.pt'), '--out', str(ev),
                 '--frames', '3', '4', '--drop-views', 'D2', 'D6', '--calibration', 'frozen_first',
                 '--score-threshold', '0.05']) == 0
    text = capsys.readouterr().out
    assert 'MODA (@0.5 m)' in text and 'IDF1' in text
    metrics = json.loads((ev / 'metrics.json').read_text())
    assert metrics['views'] == ['D1', 'D3', 'D4', 'D5', 'D7', 'D8']
    assert metrics['detection']['num_gt'] == 80
    for png in ['trajectories.png', 'heatmap_0003.png']:
        assert (ev / png).read_bytes()[:4] == b'\x89PNG'


def test_config_errors_are_clear(tmp_path):
    bad = tmp_path / 'bad.yaml'
    bad.write_text('train: [{path: x}]\nepoch: 3\n')
    with pytest.raises(ValueError, match="unknown keys \\['epoch'\\]"):
        load_config(bad)
    with pytest.raises(FileNotFoundError, match='shipped'):
        load_config('no_such_config')
    assert load_config('complex').bev.model == 'bev_small'
