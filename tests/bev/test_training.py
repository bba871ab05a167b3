"""A few training steps on the real sample reduce the loss; checkpoints resume; evaluate writes PNGs."""

import dataclasses
import json

import numpy as np
import pytest
import torch

from matrix_core.bev.config import SequenceSpec, TrainConfig, load_config
from matrix_core.bev.data import BevFrames, ground_truth_positions
from matrix_core.bev.decode import decode_detections
from matrix_core.bev.registry import build_model
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.training import seed_everything, training_step
from matrix_core.cli.main import main
from tiny_training import tiny_config

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
        model.train()  # batch statistics: after 12 steps the running ones are not settled yet
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
    cfg = tiny_config(tmp_path, matrix_sample, monkeypatch, 'epochs: 1\nseed: 3\n')
    out = tmp_path / 'run'
    assert main(['train', '--config', str(cfg), '--out', str(out)]) == 0
    assert (
        main(
            [
                'train',
                '--config',
                str(cfg),
                '--out',
                str(out),
                '--resume',
                '--epochs',
                '2',
                '--export',
                str(tmp_path / 'shipped.pt'),
            ]
        )
        == 0
    )
    shipped = torch.load(tmp_path / 'shipped.pt', weights_only=False)
    assert set(shipped) == {'model', 'settings', 'epoch', 'history', 'trained_with'} and shipped['epoch'] == 2
    history = json.loads((out / 'history.json').read_text())
    assert [h['epoch'] for h in history] == [1, 2] and 'val_moda' in history[-1]
    assert (out / 'best.pt').is_file() and (out / 'last.pt').is_file()
    capsys.readouterr()
    ev = tmp_path / 'eval'
    assert (
        main(
            [
                'evaluate',
                str(matrix_sample),
                '--checkpoint',
                str(out / 'last.pt'),
                '--out',
                str(ev),
                '--frames',
                '3',
                '4',
                '--drop-views',
                'D2',
                'D6',
                '--calibration',
                'frozen_first',
                '--score-threshold',
                '0.05',
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert 'MODA (@0.5 m)' in text and 'IDF1' in text and 'HOTA (@1 m)' in text
    metrics = json.loads((ev / 'metrics.json').read_text())
    assert metrics['views'] == ['D1', 'D3', 'D4', 'D5', 'D7', 'D8']
    assert metrics['detection']['num_gt'] == 80
    assert metrics['hota']['num_gt'] == 80 and metrics['hota']['num_pred'] == metrics['tracking']['num_pred']
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


@pytest.mark.slow
def test_offset_heads_overfit_a_few_frames(matrix_sample):
    """With the default loss weights the sub-cell offset and tracking offset heads learn their targets, and
    decoding (peak cell + offset) puts the detections closer to the people than the cell centres are."""
    torch.set_num_threads(1)
    seed_everything(0)
    settings = BevSettings(model='bev_tiny', image_width=160, image_height=96, cell_m=0.5)
    data = BevFrames(matrix_sample, settings, frames=[1, 2, 3])
    config = TrainConfig(train=[SequenceSpec(str(matrix_sample))], bev=settings, view_dropout=0.0)
    model = build_model('bev_tiny')
    opt = torch.optim.AdamW(model.parameters(), lr=3e-3)
    rng = np.random.default_rng(0)
    zero = {}
    for k in (1, 2):
        item = data[k]
        zero[k] = (
            float(item['offset'][:, item['center_mask'][0] > 0].abs().mean()),
            float(item['tracking'][:, item['tracking_mask'][0] > 0].abs().mean()),
        )
    for step in range(200):
        terms = training_step(model, [data], [(0, 1 + step % 2)], config, rng)
        opt.zero_grad()
        terms['total'].backward()
        opt.step()
    model.train()
    with torch.no_grad():
        for k in (1, 2):
            terms = training_step(model, [data], [(0, k)], config, rng)
            print(
                f"frame {k}: offset L1 {float(terms['offset']):.3f} m (zero {zero[k][0]:.3f}), "
                f"tracking L1 {float(terms['tracking']):.3f} m (zero {zero[k][1]:.3f})"
            )
            assert float(terms['offset']) < 0.5 * zero[k][0]
            assert float(terms['tracking']) < 0.5 * zero[k][1]
        x, prev = data.inputs(2), data.inputs(1)
        shape = data.grid.shape
        previous = model(prev['images'][None], prev['feat_H_grid'][None], prev['view_mask'][None], shape)['bev']
        out = model(x['images'][None], x['feat_H_grid'][None], x['view_mask'][None], shape, previous)
    dets = decode_detections(out['heatmap'][0], out['offset'][0], out['tracking'][0], data.grid, 0.3, subcell='offset')
    truth = np.array(list(ground_truth_positions(data.dataset, 2).values()))
    cells = data.grid.cell_to_world(np.round(data.grid.world_to_cell(dets.xy)))
    nearest = lambda xy: np.linalg.norm(xy[:, None] - truth[None], axis=2).min(axis=1)
    print(
        f'{len(dets)} detections, {len(truth)} people; error with offsets {np.median(nearest(dets.xy)):.3f} m, '
        f'cell centres {np.median(nearest(cells)):.3f} m'
    )
    assert len(dets) >= 0.9 * len(truth)
    assert np.median(nearest(dets.xy)) < 0.6 * np.median(nearest(cells))


def test_validation_record_weights_the_selection_score():
    from types import SimpleNamespace

    from matrix_core.bev.training import validation_record

    def result(moda, mota, idf1):
        return SimpleNamespace(detection=SimpleNamespace(moda=moda), tracking=SimpleNamespace(mota=mota, idf1=idf1))

    specs = [SequenceSpec('data/sim_a'), SequenceSpec('data/sim_b'), SequenceSpec('/x/matrix_sample', weight=2.0)]
    record = validation_record(specs, [result(0.9, 0.8, 0.7), result(0.7, 0.6, 0.5), result(0.5, 0.4, 0.3)])
    assert record['val_moda'] == pytest.approx(0.7) and record['val_idf1'] == pytest.approx(0.5)
    assert record['val_moda[matrix_sample]'] == 0.5 and record['val_mota[sim_a]'] == 0.8
    assert record['val_score'] == pytest.approx((0.9 + 0.7 + 2 * 0.5) / 4)  # not the plain mean 0.7
    with pytest.raises(ValueError, match='weight'):
        SequenceSpec('data/sim_a', weight=-1.0)


def test_the_tiny_recipe_is_the_detector_recipe_with_another_model():
    tiny, default = load_config('detector_tiny'), load_config('detector')
    assert tiny.bev == dataclasses.replace(default.bev, model='bev_tiny')
    assert tiny.out_dir == 'out/train/detector_tiny'
    assert dataclasses.replace(tiny, bev=default.bev, out_dir=default.out_dir) == default


def test_a_base_config_is_overridden_key_by_key(tmp_path):
    (tmp_path / 'a.yaml').write_text('train: [{path: x}]\nepochs: 3\nbev: {model: bev_tiny, cell_m: 0.5}\n')
    (tmp_path / 'b.yaml').write_text(f'base: {tmp_path / "a.yaml"}\nepochs: 4\nbev: {{cell_m: 0.25}}\n')
    b = load_config(tmp_path / 'b.yaml')
    assert (b.epochs, b.bev.model, b.bev.cell_m, [s.path for s in b.train]) == (4, 'bev_tiny', 0.25, ['x'])
    (tmp_path / 'a.yaml').write_text(f'base: {tmp_path / "b.yaml"}\n')
    with pytest.raises(ValueError, match='loop'):
        load_config(tmp_path / 'b.yaml')


def test_shipped_detector_recipe_validates_every_epoch_with_the_real_frames_weighted():
    config = load_config('detector')
    assert config.validate_every == 1
    real = [s for s in config.val if s.label == 'matrix_sample']
    assert len(real) == 1 and real[0].weight == sum(s.weight for s in config.val if s is not real[0])
    assert len({s.path for s in config.train}) == len(config.train) >= 12
    assert not {s.path for s in config.train} & {s.path for s in config.val}
