#!/usr/bin/env python3
"""Benchmark of the BEV fusion network on this CPU: forward time per frame (8 views, default input size
and grid) and training samples per second. Uses the real MATRIX sample's images and calibrations.

    python scripts/bench_bev.py [--model bev_small] [--threads 1] [--frames 5] [--steps 5]
                                [--width 480 --height 272 --cell-m 0.25] [--checkpoint CKPT]

``--checkpoint`` times a trained model at the input size and grid it was trained with (e.g. the shipped
``matrix_core/bev/checkpoints/detector_seed1.pt``); the defaults are BevSettings' defaults.
"""

import argparse
import os
import time
from pathlib import Path

import numpy as np
import torch

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.config import SequenceSpec, TrainConfig
from matrix_core.bev.data import BevFrames, prepare_image
from matrix_core.bev.inference import SequenceRunner
from matrix_core.bev.registry import MODELS, build_model
from matrix_core.bev.settings import BevSettings
from matrix_core.bev.training import seed_everything, training_step


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--dataset', default=os.path.join(os.environ.get('MATRIX_SHARED', '../shared'), 'matrix_sample'))
    p.add_argument('--model', default=BevSettings.model, choices=sorted(MODELS))
    p.add_argument('--threads', type=int, default=1, help='torch threads (default 1: the CI machine is shared)')
    p.add_argument('--frames', type=int, default=5, help='timed forward passes')
    p.add_argument('--steps', type=int, default=5, help='timed training steps')
    p.add_argument('--width', type=int, default=BevSettings.image_width, help='network input width (px)')
    p.add_argument('--height', type=int, default=BevSettings.image_height, help='network input height (px)')
    p.add_argument('--cell-m', type=float, default=BevSettings.cell_m, help='BEV cell size (m)')
    p.add_argument('--checkpoint', help='time this trained model with its own settings instead')
    args = p.parse_args()
    torch.set_num_threads(args.threads)
    seed_everything(0)
    if args.checkpoint:
        model, settings = load_model(args.checkpoint)
        args.model = settings.model
    else:
        settings = BevSettings(model=args.model, image_width=args.width, image_height=args.height, cell_m=args.cell_m)
        model = build_model(args.model)
    data = BevFrames(Path(args.dataset), settings)
    n_params = sum(q.numel() for q in model.parameters())
    print(
        f'model {args.model}: {n_params / 1e6:.2f} M parameters; input {settings.image_width}x{settings.image_height}, '
        f'{len(data.views)} views, grid {data.grid.shape[1]}x{data.grid.shape[0]} cells of {settings.cell_m} m; '
        f'torch threads {args.threads}'
    )
    frames = [data.frames[i % len(data.frames)] for i in range(args.frames + 1)]
    inputs = [data.inputs(f) for f in frames]  # decode/resize outside the timing
    model.eval()
    times, previous = [], None
    with torch.no_grad():
        for x in inputs:
            t0 = time.perf_counter()
            previous = model(
                x['images'][None], x['feat_H_grid'][None], x['view_mask'][None], data.grid.shape, previous
            )['bev']
            times.append(time.perf_counter() - t0)
    fwd = np.array(times[1:])  # the first call warms up
    print(
        f'model forward per frame (8 views, {settings.image_width}x{settings.image_height}): mean '
        f'{1000 * fwd.mean():.0f} ms, min {1000 * fwd.min():.0f} ms'
    )
    runner = SequenceRunner(model, settings, data.grid)
    times = []
    for f, x in zip(frames, inputs):
        t0 = time.perf_counter()
        runner.step(f, x['images'], x['feat_H_grid'], x['view_mask'])
        times.append(time.perf_counter() - t0)
    fwd = np.array(times[1:])
    print(
        f'forward + decode per frame (8 views): mean {1000 * fwd.mean():.0f} ms, min {1000 * fwd.min():.0f} ms '
        f'-> {1 / fwd.mean():.2f} frames/s'
    )
    sizes = [data.dataset.load_image(v, frames[0]) for v in data.views]
    t0 = time.perf_counter()
    for img in sizes:
        prepare_image(img, (settings.image_width, settings.image_height))
    print(
        f'image preparation (resize + normalise, {sizes[0].shape[1]}x{sizes[0].shape[0]} -> input) per frame '
        f'(8 views): {1000 * (time.perf_counter() - t0):.0f} ms'
    )
    config = TrainConfig(train=[SequenceSpec(args.dataset)], bev=settings, view_dropout=0.0)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-3)
    rng = np.random.default_rng(0)
    model.train()
    for _ in range(len(data)):
        data[_]  # fill the image cache
    times = []
    for step in range(args.steps + 1):
        t0 = time.perf_counter()
        terms = training_step(model, [data], [(0, 1 + step % (len(data) - 1))], config, rng)
        opt.zero_grad()
        terms['total'].backward()
        opt.step()
        times.append(time.perf_counter() - t0)
    tr = np.array(times[1:])
    print(
        f'training step (batch 1, with the previous frame\'s forward for temporal fusion): mean {tr.mean():.2f} s '
        f'-> {1 / tr.mean():.2f} samples/s'
    )
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
