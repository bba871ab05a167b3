"""Saving and loading trained BEV models (state dict + the settings they were trained with)."""

import dataclasses
from pathlib import Path

import torch

from matrix_core.bev.registry import build_model
from matrix_core.bev.settings import BevSettings
from matrix_core.output_paths import atomic_path


def save_checkpoint(path, model, settings: BevSettings, **extra) -> None:
    """Write ``{'model', 'settings', **extra}`` atomically (a temp file then rename)."""
    with atomic_path(path) as tmp:
        torch.save({'model': model.state_dict(), 'settings': dataclasses.asdict(settings), **extra}, tmp)


def load_checkpoint(path, map_location='cpu') -> dict:
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f'no checkpoint {path}')
    return torch.load(path, map_location=map_location, weights_only=False)


def load_model(path, settings_overrides: dict = None) -> tuple:
    """(model in eval mode, BevSettings) from a checkpoint; ``settings_overrides`` change decoding only
    (threshold, NMS, ...) - grid and model fields must match the training ones."""
    ckpt = load_checkpoint(path)
    settings = BevSettings(**{**ckpt['settings'], **(settings_overrides or {})})
    model = build_model(settings.model, temporal=settings.temporal)
    model.load_state_dict(ckpt['model'])
    return model.eval(), settings


def export_checkpoint(src, dst, trained_with: str = '') -> Path:
    """Write the shippable part of a training checkpoint (``model``, ``settings``, ``epoch``, ``history``,
    ``trained_with``, and ``averaged`` and ``site`` when it has them: no optimizer state, a third of the size)
    from ``src`` (e.g. ``last.pt``) to ``dst``."""
    ckpt = load_checkpoint(src)
    dst = Path(dst)
    dst.parent.mkdir(parents=True, exist_ok=True)
    tmp = dst.with_suffix(dst.suffix + '.tmp')
    shipped = {
        'model': ckpt['model'],
        'settings': ckpt['settings'],
        'epoch': ckpt.get('epoch'),
        'history': ckpt.get('history', []),
        'trained_with': trained_with,
    }
    if 'averaged' in ckpt:  # weights averaged over these epochs (bev/averaging.py)
        shipped['averaged'] = ckpt['averaged']
    if 'site' in ckpt:  # the site it was trained for (train --site, bev/site_training.py)
        shipped['site'] = ckpt['site']
    torch.save(shipped, tmp)
    tmp.replace(dst)
    return dst
