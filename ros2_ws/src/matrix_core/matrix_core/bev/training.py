"""Training loop of the BEV network: seeded, resumable, with progress bars, checkpoints and periodic
validation (validation itself lives in ``evaluation.py``)."""

import dataclasses
import json
import os
import random
from pathlib import Path

import numpy as np
import torch

from matrix_core.bev.averaging import average_state_dicts, recompute_batch_norm
from matrix_core.bev.checkpoint import load_checkpoint, save_checkpoint
from matrix_core.bev.config import TrainConfig
from matrix_core.bev.data import BevFrames
from matrix_core.bev.evaluation import evaluate
from matrix_core.bev.losses import bev_loss
from matrix_core.bev.registry import build_model
from matrix_core.device import DEFAULT_DEVICE, model_device, resolve_device
from matrix_core.output_paths import atomic_write_text

TARGET_KEYS = ('heatmap', 'offset', 'tracking', 'center_mask', 'tracking_mask')


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


def open_sequences(specs: list, config: TrainConfig, training: bool = False) -> list:
    """A :class:`BevFrames` per sequence spec (paths may use ``$MATRIX_SHARED`` and ``~``); ``training``
    sequences get ``config.augment`` (validation is never augmented)."""
    augment = config.augment if training else None
    out = []
    for spec in specs:
        path = Path(os.path.expanduser(os.path.expandvars(spec.path)))
        cdir = os.path.expanduser(os.path.expandvars(spec.calibration_dir)) if spec.calibration_dir else None
        probe = BevFrames(
            path,
            config.bev,
            calibration=spec.calibration,
            views=spec.views,
            cache_images=config.cache_images,
            calibration_dir=cdir,
            augment=augment,
        )
        frames = spec.frame_list(probe.frames)
        out.append(
            probe
            if frames == list(probe.frames)
            else BevFrames(path, config.bev, frames, spec.calibration, spec.views, config.cache_images, cdir, augment)
        )
    return out


def load_initial_weights(model, config: TrainConfig, log=print) -> None:
    """Load ``config.init``'s weights into ``model`` (fine-tuning); ValueError naming the checkpoint when its
    network is not the config's (another model or temporal setting: its weights would not fit)."""
    ckpt = load_checkpoint(config.init)
    trained = ckpt.get('settings') or {}
    theirs = (trained.get('model'), trained.get('temporal', True))
    ours = (config.bev.model, config.bev.temporal)
    if theirs != ours:
        raise ValueError(
            f'init checkpoint {config.init}: network {theirs[0]} (temporal {theirs[1]}), but the config trains '
            f'{ours[0]} (temporal {ours[1]})'
        )
    model.load_state_dict(ckpt['model'])
    log(f'fine-tuning from {config.init} ({theirs[0]}, cells of {trained.get("cell_m")} m)')


def drop_views(mask: torch.Tensor, p: float, min_views: int, rng: np.random.Generator) -> torch.Tensor:
    """Randomly switch off views of a (V,) bool mask with probability ``p`` each, keeping >= min_views."""
    present = np.flatnonzero(mask.numpy())
    drop = present[rng.random(len(present)) < p]
    drop = drop[: max(len(present) - min_views, 0)]
    out = mask.clone()
    out[torch.as_tensor(drop, dtype=torch.long)] = False
    return out


def augment_rng(seq: BevFrames, rng: np.random.Generator):
    """A generator of its own for one sample's augmentation, drawn from the epoch's ``rng`` (seeded runs
    stay deterministic, and the number of draws an augmentation makes does not shift the view dropout);
    None, without touching ``rng``, when the sequence is not augmented (runs then match those before
    augmentation existed)."""
    return None if seq.augment is None else np.random.default_rng(rng.integers(2**63))


def learning_rate(config: TrainConfig, step: int, total_steps: int) -> float:
    """Learning rate at global ``step`` of ``total_steps`` (a pure function of the step, so resume needs no
    scheduler state): constant, or cosine from ``lr`` down to ``lr_min_ratio * lr``."""
    if config.lr_schedule == 'constant' or total_steps <= 1:
        return config.lr
    t = min(step / (total_steps - 1), 1.0)
    low = config.lr * config.lr_min_ratio
    return low + 0.5 * (config.lr - low) * (1.0 + np.cos(np.pi * t))


def _batch(items: list, device) -> dict:
    """The tensors of ``items`` stacked and on ``device`` (on the CPU: no copy)."""
    return {
        k: torch.stack([it[k] for it in items]).to(device) for k in items[0] if isinstance(items[0][k], torch.Tensor)
    }


def training_step(model, sequences, picks, config: TrainConfig, rng) -> dict:
    """Loss terms of one batch; ``picks`` = [(sequence index, item index)]. With temporal fusion, the
    previous frame's BEV features are computed first (no gradient) and fed in. The batch is built on the CPU and
    copied to the model's device once."""
    device = model_device(model)
    items, prev_inputs, prev_valid = [], [], []
    for si, k in picks:
        seq = sequences[si]
        item = seq.sample(k, augment_rng(seq, rng))
        item['view_mask'] = drop_views(item['view_mask'], config.view_dropout, config.min_views, rng)
        items.append(item)
        has_prev = k > 0
        prev_valid.append(has_prev)
        if config.bev.temporal:
            x = seq.inputs(seq.frames[k - 1] if has_prev else seq.frames[k], augment_rng(seq, rng))
            x['view_mask'] = drop_views(x['view_mask'], config.view_dropout, config.min_views, rng)
            prev_inputs.append(x)
    batch = _batch(items, device)
    grid_shape = sequences[picks[0][0]].grid.shape
    previous = valid = None
    if config.bev.temporal:
        p = _batch(prev_inputs, device)
        with torch.no_grad():
            previous = model(p['images'], p['feat_H_grid'], p['view_mask'], grid_shape)['bev']
        valid = torch.tensor(prev_valid, device=device)
    out = model(batch['images'], batch['feat_H_grid'], batch['view_mask'], grid_shape, previous, valid)
    targets = {k: batch[k] for k in TARGET_KEYS}
    if not config.bev.temporal or not any(prev_valid):
        targets['tracking_mask'] = torch.zeros_like(targets['tracking_mask'])
    return bev_loss(out, targets, config.loss_weights)


def validation_record(specs: list, results: list) -> dict:
    """History entries of one validation: the plain means ``val_moda``, ``val_mota``, ``val_idf1`` over the
    sequences, each sequence's ``val_moda[LABEL]`` / ``val_mota[LABEL]`` / ``val_idf1[LABEL]``, and
    ``val_score``, the MODA averaged with each spec's ``weight``: what selects ``best.pt``."""
    record = {}
    for key, get in (
        ('moda', lambda r: r.detection.moda),
        ('mota', lambda r: r.tracking.mota),
        ('idf1', lambda r: r.tracking.idf1),
    ):
        record[f'val_{key}'] = float(np.mean([get(r) for r in results]))
        record.update({f'val_{key}[{spec.label}]': float(get(r)) for spec, r in zip(specs, results)})
    weights = np.array([spec.weight for spec in specs], dtype=float)
    modas = np.array([r.detection.moda for r in results])
    record['val_score'] = float(weights @ modas / weights.sum()) if weights.sum() > 0 else float(modas.mean())
    return record


def train(
    config: TrainConfig,
    out_dir=None,
    resume: bool = False,
    progress: bool = True,
    log=print,
    device: str = DEFAULT_DEVICE,
    tags: dict = None,
) -> list:
    """Train; returns the history (one dict per epoch). Writes ``last.pt`` every epoch, ``best.pt`` at the
    best ``val_score`` (validation MODA weighted per sequence, :func:`validation_record`), ``history.json``;
    ``resume`` continues from ``last.pt`` (same config). ``device``: where the network trains and validates
    (``matrix_core.device``; resolved first, ``auto``'s choice told to ``log``); samples are made on the CPU.
    ``config.init``: the weights of a fresh run's first step. ``tags``: entries every checkpoint written
    carries (``train --site``: the site it is for)."""
    from tqdm import tqdm

    device = resolve_device(device, log)
    out_dir = Path(out_dir or config.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(config.num_threads)
    seed_everything(config.seed)
    sequences = open_sequences(config.train, config, training=True)
    shapes = {s.grid.shape for s in sequences}
    if len(shapes) != 1:
        raise ValueError(f'training sequences have different BEV grids {shapes}: set bev.area in the config')
    val_sequences = open_sequences(config.val, config) if config.val else []
    model = build_model(config.bev.model, temporal=config.bev.temporal)
    last = out_dir / 'last.pt'
    if config.init and not (resume and last.is_file()):
        load_initial_weights(model, config, log)
    model = model.to(device)
    tags = dict(tags or {})
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    start_epoch, history, best = 0, [], -np.inf
    if resume and last.is_file():
        ckpt = load_checkpoint(last)
        model.load_state_dict(ckpt['model'])
        optimizer.load_state_dict(ckpt['optimizer'])
        start_epoch, history, best = ckpt['epoch'], ckpt['history'], ckpt['best']
        torch.set_rng_state(ckpt['torch_rng'])
        log(f'resumed from {last} after epoch {start_epoch}')
    index = [(si, k) for si, s in enumerate(sequences) for k in range(len(s))]
    steps_per_epoch = -(-len(index) // config.batch_size)
    if config.max_steps_per_epoch:
        steps_per_epoch = min(steps_per_epoch, config.max_steps_per_epoch)
    total_steps = steps_per_epoch * config.epochs
    for epoch in range(start_epoch, config.epochs):
        rng = np.random.default_rng(config.seed * 1000 + epoch)
        order = [index[i] for i in rng.permutation(len(index))]
        batches = [order[i : i + config.batch_size] for i in range(0, len(order), config.batch_size)]
        if config.max_steps_per_epoch:
            batches = batches[: config.max_steps_per_epoch]
        model.train()
        sums = {}
        bar = tqdm(batches, desc=f'epoch {epoch + 1}/{config.epochs}', unit='batch', disable=not progress)
        for i, picks in enumerate(bar):
            for group in optimizer.param_groups:
                group['lr'] = learning_rate(config, epoch * steps_per_epoch + i, total_steps)
            terms = training_step(model, sequences, picks, config, rng)
            optimizer.zero_grad()
            terms['total'].backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
            optimizer.step()
            for k, v in terms.items():
                sums[k] = sums.get(k, 0.0) + float(v.detach())
            bar.set_postfix(loss=f'{float(terms["total"].detach()):.3f}')
        record = {'epoch': epoch + 1, **{f'loss_{k}': v / max(len(batches), 1) for k, v in sums.items()}}
        if val_sequences and ((epoch + 1) % config.validate_every == 0 or epoch + 1 == config.epochs):
            model.eval()
            results = [evaluate(model, s, config.tracker, progress=progress) for s in val_sequences]
            record.update(validation_record(config.val, results))
            if record['val_score'] > best:
                best = record['val_score']
                save_checkpoint(out_dir / 'best.pt', model, config.bev, epoch=epoch + 1, metrics=record, **tags)
        history.append(record)
        log(' '.join(f'{k}={v:.4f}' if isinstance(v, float) else f'{k}={v}' for k, v in record.items()))
        save_checkpoint(
            last,
            model,
            config.bev,
            optimizer=optimizer.state_dict(),
            epoch=epoch + 1,
            history=history,
            best=best,
            torch_rng=torch.get_rng_state(),
            config=json.loads(json.dumps(dataclasses.asdict(config), default=str)),
            **tags,
        )
        if config.average_epochs:
            save_checkpoint(out_dir / f'epoch{epoch + 1}.pt', model, config.bev, epoch=epoch + 1, **tags)
        atomic_write_text(out_dir / 'history.json', json.dumps(history, indent=2))
    if config.average_epochs and not any('averaged' in h for h in history):
        entry = average_last_epochs(config, out_dir, sequences, val_sequences, best, progress, device, tags)
        history.append(entry)
        log(' '.join(f'{k}={v:.4f}' if isinstance(v, float) else f'{k}={v}' for k, v in entry.items()))
        atomic_write_text(out_dir / 'history.json', json.dumps(history, indent=2))
    return history


def average_last_epochs(
    config: TrainConfig,
    out_dir: Path,
    sequences: list,
    val_sequences: list,
    best: float,
    progress: bool = True,
    device='cpu',
    tags: dict = None,
) -> dict:
    """The mean of the weights of the last ``config.average_epochs`` epochs (``out_dir/epochN.pt``), its
    batch-norm statistics measured over ``config.bn_samples`` training steps (augmented, views dropped, as
    in training; seeded), written to ``averaged.pt`` and, when its ``val_score`` beats ``best`` (the best
    epoch's), to ``best.pt``. Returns its history record: ``epoch`` (the last), ``averaged`` (the epochs) and
    the validation entries of :func:`validation_record`."""
    epochs = list(range(config.epochs - config.average_epochs + 1, config.epochs + 1))
    missing = [e for e in epochs if not (out_dir / f'epoch{e}.pt').is_file()]
    if missing:
        raise FileNotFoundError(
            f'weight averaging needs {out_dir}/epochN.pt of epochs {missing} (written by a run with average_epochs set)'
        )
    model = build_model(config.bev.model, temporal=config.bev.temporal)
    model.load_state_dict(average_state_dicts([load_checkpoint(out_dir / f'epoch{e}.pt')['model'] for e in epochs]))
    model = model.to(device)
    rng = np.random.default_rng(config.seed * 1000 + config.epochs)
    index = [(si, k) for si, s in enumerate(sequences) for k in range(len(s))]
    picks = [index[i] for i in rng.permutation(len(index))[: config.bn_samples]]
    recompute_batch_norm(model, lambda m: [training_step(m, sequences, [p], config, rng) for p in picks])
    record = {'epoch': config.epochs, 'averaged': epochs}
    if val_sequences:
        model.eval()
        record.update(
            validation_record(
                config.val, [evaluate(model, s, config.tracker, progress=progress) for s in val_sequences]
            )
        )
    extra = {'epoch': config.epochs, 'averaged': epochs, 'metrics': record, **(tags or {})}
    save_checkpoint(out_dir / 'averaged.pt', model, config.bev, **extra)
    if record.get('val_score', -np.inf) > best:
        save_checkpoint(out_dir / 'best.pt', model, config.bev, **extra)
    return record
