"""Weight averaging over the last epochs (bev/averaging.py) and its place at the end of training."""

import json

import pytest
import torch
from torch import nn

from matrix_core.bev.averaging import average_state_dicts, recompute_batch_norm
from matrix_core.bev.checkpoint import load_checkpoint
from matrix_core.bev.config import load_config
from matrix_core.bev.training import train
from tiny_training import tiny_config


def test_average_state_dicts_means_floats_and_keeps_the_last_counters():
    a = {'w': torch.tensor([1.0, 2.0]), 'n': torch.tensor(3)}
    b = {'w': torch.tensor([3.0, 6.0]), 'n': torch.tensor(7)}
    out = average_state_dicts([a, b])
    assert torch.equal(out['w'], torch.tensor([2.0, 4.0])) and int(out['n']) == 7
    with pytest.raises(ValueError, match='different keys'):
        average_state_dicts([a, {'w': a['w']}])
    with pytest.raises(ValueError, match='no state dicts'):
        average_state_dicts([])


def test_recompute_batch_norm_measures_the_plain_mean_of_what_it_is_shown():
    torch.manual_seed(0)
    model = nn.Sequential(nn.Linear(3, 2), nn.BatchNorm1d(2)).eval()
    model[1].running_mean.fill_(50.0)  # stale statistics of other weights
    batches = [torch.randn(8, 3) + k for k in range(4)]

    def show(m):
        for x in batches:
            m(x)

    assert recompute_batch_norm(model, show) == 1
    with torch.no_grad():
        expected = torch.stack([model[0](x).mean(dim=0) for x in batches]).mean(dim=0)
    assert torch.allclose(model[1].running_mean, expected, atol=1e-5)
    assert not model.training and model[1].momentum == 0.1  # mode and momentum restored


@pytest.mark.slow
def test_training_ends_with_the_average_of_the_last_epochs(matrix_sample, tmp_path, monkeypatch):
    cfg = tiny_config(tmp_path, matrix_sample, monkeypatch, 'epochs: 3\naverage_epochs: 2\nbn_samples: 3\nseed: 5\n')
    torch.set_num_threads(1)
    out = tmp_path / 'run'
    history = train(load_config(cfg), out, progress=False, log=lambda *_: None)
    assert [h['epoch'] for h in history] == [1, 2, 3, 3] and history[-1]['averaged'] == [2, 3]
    assert 'val_score' in history[-1] and json.loads((out / 'history.json').read_text()) == history
    averaged = load_checkpoint(out / 'averaged.pt')
    e2, e3 = (load_checkpoint(out / f'epoch{e}.pt')['model'] for e in (2, 3))
    name = next(k for k in averaged['model'] if k.endswith('weight') and averaged['model'][k].dim() == 4)
    assert torch.allclose(averaged['model'][name], (e2[name] + e3[name]) / 2)
    best = load_checkpoint(out / 'best.pt')
    assert best['metrics']['val_score'] == max(h['val_score'] for h in history)
    # resuming the finished run makes the same average again (seeded), the epochs untouched
    again = train(load_config(cfg), out, resume=True, progress=False, log=lambda *_: None)
    assert again[:3] == history[:3] and again[3]['val_score'] == pytest.approx(history[3]['val_score'])
