#!/usr/bin/env python3
"""Benchmark of the BEV fusion network on this CPU: forward time per frame (8 views, default input size
and grid) and training samples per second. Uses the real MATRIX sample's images and calibrations.

    python scripts/bench_bev.py [--model bev_small] [--threads 1] [--frames 5] [--steps 5]
"""

import argparse
import os
import time
from pathlib import Path

import numpy as np
import torch

from matrix_core.bev.config import SequenceSpec, TrainConfig
from matrix_core.bev.data import BevFrames
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
    args = p.parse_args()
    torch.set_num_threads(args.threads)
    seed_everything(0)
    settings = BevSettings(model=args.model)
    data = BevFrames(Path(args.dataset), settings)
    model = build_model(args.model)
    n_params = sum(q.numel() for q in model.parameters())
    print(f'model {args.model}: {n_params / 1e6:.2f} M parameters; input {settings.image_width}x{settings.image_height}, '
          f'{len(data.views)} views, grid {data.grid.shape[1]}x{data.grid.shape[0]} cells of {settings.cell_m} m; '
          f'torch threads {args.threads}')
    frames = [data.frames[i % len(data.frames)] for i in range(args.frames + 1)]
    inputs = [data.inputs(f) for f in frames]          # decode/resize outside the timing
    runner = SequenceRunner(model, settings, data.grid)
    times = []
    for f, x in zip(frames, inputs):
        t0 = time.perf_counter()
        runner.step(f, x['images'], x['feat_H_grid'], x['view_mask'])
        times.append(time.perf_counter() - t0)
    fwd = np.array(times[1:])                          # the first call warms up
    print(f'forward + decode per frame (8 views): mean {1000 * fwd.mean():.0f} ms, min {1000 * fwd.min():.0f} ms '
          f'-> {1 / fwd.mean():.2f} frames/s')
    config = TrainConfig(train=[SequenceSpec(args.dataset)], bev=settings, view_dropout=0.0)
    opt = torch.optim.AdamW(model.parameters(), lr=1e-3)
    rng = np.random.default_rng(0)
    model.train()
    for _ in range(len(data)):
        data[_]                                        # fill the image cache
    times = []
    for step in range(args.steps + 1):
        t0 = time.perf_counter()
        terms = training_step(model, [data], [(0, 1 + step % (len(data) - 1))], config, rng)
        opt.zero_grad()
        terms['total'].backward()
        opt.step()
        times.append(time.perf_counter() - t0)
    tr = np.array(times[1:])
    print(f'training step (batch 1, with the previous frame\'s forward for temporal fusion): mean {tr.mean():.2f} s '
          f'-> {1 / tr.mean():.2f} samples/s')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
