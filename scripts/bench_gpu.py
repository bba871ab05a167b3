#!/usr/bin/env python3
"""GPU benchmark of the BEV network as the fuse node runs it, on the shipped default checkpoint (no ROS needed).

For each number of views (8, 16, 32, 64) of 1920x1080 JPEG frames: the CPU's share (JPEG decode at the reduced
scale the node uses, resize, normalise; per view, one thread), the copy of the frame's network inputs to the
device, the lifting alone (sampling taps of every view's new homography, the gather and the view pooling), the
whole network (encoder, lifting, aggregation, temporal block, heatmap: a moving camera's homography changes every
frame, so the taps are recomputed every frame) and the decoding (peaks, heads at the peaks, metres on the CPU).
Then training steps per second (the trainer's step: previous-frame pass, forward, loss, backward, AdamW) and the
CPU-device equality check (heatmap logits within 1e-3 and the same detections, as tests/bev/test_device.py).

Frames: the real MATRIX sample's 8 views and cameras when found (``--sample``, default ``$MATRIX_SHARED`` or
``shared/`` next to the repository), cycled for more views; else 8 synthetic cameras on a ring with noise
images. Prints one markdown table, headed by the device's name. See docs/gpu.md.

On a machine with CUDA and PyTorch (no ROS, no colcon build: the script finds ``ros2_ws/src/matrix_core``
itself; it needs numpy, opencv-python, scipy, pyyaml and tqdm besides torch, as requirements.txt pins them):

    python scripts/bench_gpu.py                      # device auto: the first CUDA GPU
    python scripts/bench_gpu.py --device cuda:1 --views 8 64
    python scripts/bench_gpu.py --device cpu --quick # a smoke run (2 and 4 views, few iterations)

Goals (docs/gpu.md): the fuse network (copy + network + decoding) at >= 30 frames/s for 8 views at 1080p and
>= 10 frames/s for 64 views.
"""

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch

ROOT = Path(__file__).resolve().parent.parent
try:
    import matrix_core  # noqa: F401  (installed: make setup, scripts/env.sh)
except ImportError:  # a bare checkout on a GPU machine: the core package is plain Python
    sys.path.insert(0, str(ROOT / 'ros2_ws' / 'src' / 'matrix_core'))

from matrix_core.bev.checkpoint import load_model  # noqa: E402
from matrix_core.bev.data import prepare_image  # noqa: E402
from matrix_core.bev.decode import Peaks, find_peaks, peak_detections  # noqa: E402
from matrix_core.bev.frame_network import FrameNetwork  # noqa: E402
from matrix_core.bev.lifting import feat_H_grid  # noqa: E402
from matrix_core.bev.losses import bev_loss  # noqa: E402
from matrix_core.bev.registry import build_model  # noqa: E402
from matrix_core.bev.targets import bev_targets  # noqa: E402
from matrix_core.datasets.matrix_conventions import MATRIX_AREA  # noqa: E402
from matrix_core.device import resolve_device  # noqa: E402
from matrix_core.fusion.settings import DEFAULT_CHECKPOINT, shipped_checkpoint  # noqa: E402
from matrix_core.fusion.views import jpeg_reduction  # noqa: E402

FULL_SIZE = (1920, 1080)
REDUCED_FLAGS = {1: cv2.IMREAD_COLOR, 2: cv2.IMREAD_REDUCED_COLOR_2, 4: cv2.IMREAD_REDUCED_COLOR_4}
REDUCED_FLAGS[8] = cv2.IMREAD_REDUCED_COLOR_8


def default_sample() -> Path:
    return Path(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared')) / 'matrix_sample'


def ring_cameras(n: int, area: list, rng) -> list:
    """(3, 3) img_H_ground of ``n`` 1920x1080 cameras 12 m up on a circle around the area, looking at its centre."""
    x0, y0, x1, y1 = area
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    radius = 0.6 * max(x1 - x0, y1 - y0)
    K = np.array([[1400.0, 0, 959.5], [0, 1400.0, 539.5], [0, 0, 1]])
    out = []
    for k in range(n):
        a = 2 * np.pi * k / n + rng.uniform(-0.1, 0.1)
        eye = centre + np.array([radius * np.cos(a), radius * np.sin(a), 12.0])
        forward = (centre - eye) / np.linalg.norm(centre - eye)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        R = np.stack([right, down, forward])  # rows: camera x, y, z in world coordinates
        t = -R @ eye
        out.append(K @ np.column_stack([R[:, 0], R[:, 1], t]))  # ground plane z = 0
    return out


def source_frames(sample: Path, area: list, rng) -> tuple:
    """(JPEG bytes per camera, img_H_ground per camera, the area, what they are)."""
    if sample.is_dir():
        from matrix_core.datasets import open_dataset

        ds = open_dataset(sample)
        frame = ds.frames[0]
        images = [ds.load_image(v, frame) for v in ds.views]
        if all((im.shape[1], im.shape[0]) == FULL_SIZE for im in images):
            jpegs = [cv2.imencode('.jpg', im, [cv2.IMWRITE_JPEG_QUALITY, 90])[1] for im in images]
            homographies = [ds.camera(v, frame).img_H_ground() for v in ds.views]
            return jpegs, homographies, list(ds.area), f'real MATRIX sample frame {frame}, {len(images)} cameras'
    noise = [rng.integers(0, 256, (FULL_SIZE[1], FULL_SIZE[0], 3), dtype=np.uint8) for _ in range(8)]
    jpegs = [cv2.imencode('.jpg', cv2.GaussianBlur(im, (0, 0), 3), [cv2.IMWRITE_JPEG_QUALITY, 90])[1] for im in noise]
    return jpegs, ring_cameras(8, area, rng), list(area), 'synthetic: 8 ring cameras, noise images'


def prepare(jpeg, input_size: tuple) -> np.ndarray:
    """One view's network input from its JPEG, as the fuse node makes it (reduced decode, resize, normalise)."""
    r = jpeg_reduction(FULL_SIZE, input_size)
    return prepare_image(cv2.imdecode(jpeg, REDUCED_FLAGS[r]), input_size)


class Timer:
    """Wall time of a block with the device synchronised at both ends (GPU work is asynchronous)."""

    def __init__(self, device):
        self.device = device

    def __call__(self, fn):
        self._sync()
        t0 = time.perf_counter()
        result = fn()
        self._sync()
        return result, 1e3 * (time.perf_counter() - t0)

    def _sync(self):
        if self.device.type == 'cuda':
            torch.cuda.synchronize(self.device)


def decode(net, out, grid, s):
    """Detections of one frame (what ``SequenceRunner.step`` does after the network)."""
    peaks = find_peaks(out.heatmap, grid, s.score_threshold, s.nms_radius_m, s.max_detections)
    tracking, offset = net.heads_at(out.fused, peaks.rows, peaks.cols, offset=s.subcell == 'offset')
    peaks = Peaks(peaks.scores.cpu(), peaks.rows.cpu(), peaks.cols.cpu(), peaks.score.cpu())
    return peak_detections(peaks, grid, tracking.cpu(), None if offset is None else offset.cpu(), s.subcell)


def median(values) -> float:
    return statistics.median(values) if values else float('nan')


def bench_views(n_views, prepared, fh_cameras, bev, model, device, grid, iterations, warm_up) -> dict:
    """Median ms per frame of each stage for ``n_views`` views (cameras cycled)."""
    net = FrameNetwork(model, grid.shape)
    timer = Timer(device)
    images = np.stack([prepared[k % len(prepared)] for k in range(n_views)])
    fh = torch.from_numpy(np.stack([fh_cameras[k % len(fh_cameras)] for k in range(n_views)]).astype(np.float32))
    mask = torch.ones(n_views, dtype=torch.bool)
    times = {'upload': [], 'lifting': [], 'network': [], 'decode': []}
    previous = None
    for k in range(warm_up + iterations):
        moved = fh * (1.0 + 1e-5 * (k + 1))  # same projection, new bytes: the taps are recomputed (a moving drone)
        x, t_upload = timer(lambda: torch.from_numpy(images).to(device))
        out, t_network = timer(lambda: net(x, moved, mask, previous))
        _, t_decode = timer(lambda: decode(net, out, grid, bev))
        previous = out
        with torch.no_grad():
            feats = net.encoder(x.contiguous(memory_format=torch.channels_last))
        lifted = fh * (1.0 - 1e-5 * (k + 1))  # new bytes again: the lifting timed alone recomputes its taps too

        @torch.no_grad()
        def lift():
            taps = net._taps_of(list(range(n_views)), lifted, feats.shape[-2:])
            return net._lift_and_pool(feats, taps, n_views)

        _, t_lifting = timer(lift)
        if k >= warm_up:
            for name, t in (('upload', t_upload), ('network', t_network), ('decode', t_decode), ('lifting', t_lifting)):
                times[name].append(t)
    return {name: median(v) for name, v in times.items()}


def bench_training(bev, grid, prepared, fh_cameras, n_views, device, steps, warm_up, rng) -> float:
    """Median ms of one training step (batch 1, ``n_views`` views, temporal pass first, as ``training_step``)."""
    model = build_model(bev.model, temporal=bev.temporal).to(device).train()
    optimizer = torch.optim.AdamW(model.parameters(), lr=1e-3, weight_decay=1e-4)
    images = torch.from_numpy(np.stack([prepared[k % len(prepared)] for k in range(n_views)]))[None]
    fh = torch.from_numpy(np.stack([fh_cameras[k % len(fh_cameras)] for k in range(n_views)]).astype(np.float32))
    mask = torch.ones(1, n_views, dtype=torch.bool)
    x0, y0 = grid.x_min, grid.y_min
    w, h = grid.x_max - grid.x_min, grid.y_max - grid.y_min
    people = {i: np.array([x0 + rng.uniform(0.1, 0.9) * w, y0 + rng.uniform(0.1, 0.9) * h]) for i in range(40)}
    before = {i: p + rng.normal(0, 0.2, 2) for i, p in people.items()}
    targets = {k: torch.from_numpy(v)[None] for k, v in bev_targets(grid, people, before, bev.heatmap_sigma_m).items()}
    timer = Timer(device)

    def step():
        x, f, m = images.to(device), fh[None].to(device), mask.to(device)
        t = {k: v.to(device) for k, v in targets.items()}
        with torch.no_grad():
            previous = model(x, f, m, grid.shape)['bev'] if bev.temporal else None
        valid = torch.ones(1, dtype=torch.bool, device=device) if bev.temporal else None
        loss = bev_loss(model(x, f, m, grid.shape, previous, valid), t)['total']
        optimizer.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 10.0)
        optimizer.step()

    times = [timer(step)[1] for _ in range(warm_up + steps)]
    return median(times[warm_up:])


def equality(prepared, fh_cameras, bev, device, grid, frames) -> dict:
    """CPU against ``device`` on the same frames (temporal features carried): the largest heatmap logit difference
    and the largest detection position difference (metres; inf when the detection counts differ)."""
    nets = [FrameNetwork(load_model(shipped_checkpoint())[0].to(d), grid.shape) for d in (torch.device('cpu'), device)]
    images = torch.from_numpy(np.stack(prepared))
    fh = torch.from_numpy(np.stack(fh_cameras).astype(np.float32))
    mask = torch.ones(len(prepared), dtype=torch.bool)
    previous, logit, position, detections = [None, None], 0.0, 0.0, 0
    for _ in range(frames):
        outs = [net(images, fh, mask, prev) for net, prev in zip(nets, previous)]
        logit = max(logit, float((outs[0].heatmap - outs[1].heatmap.cpu()).abs().max()))
        dets = [decode(net, out, grid, bev) for net, out in zip(nets, outs)]
        if len(dets[0]) != len(dets[1]):
            position = float('inf')
        elif len(dets[0]):
            a, b = (d.xy[np.lexsort((np.round(d.xy[:, 1], 2), np.round(d.xy[:, 0], 2)))] for d in dets)
            position = max(position, float(np.abs(a - b).max()))
        detections += len(dets[0])
        previous = outs
    return {'logit': logit, 'position': position, 'detections': detections}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--device', default='auto', help='auto | cpu | cuda | cuda:N (matrix_core.device; default auto)')
    p.add_argument('--views', type=int, nargs='+', help='view counts (default 8 16 32 64; --quick: 2 4)')
    p.add_argument('--iterations', type=int, help='timed frames per view count (default 30; --quick: 3)')
    p.add_argument('--train-views', type=int, help='views per training sample (default 8; --quick: 2)')
    p.add_argument('--threads', type=int, default=1, help='torch CPU threads (default 1, as the fuse node)')
    p.add_argument('--quick', action='store_true', help='a smoke run: small view counts, few iterations')
    p.add_argument('--sample', type=Path, default=default_sample(), help='real MATRIX sample folder (if present)')
    p.add_argument('--checkpoint', default=DEFAULT_CHECKPOINT, help='shipped checkpoint name (default: the default)')
    args = p.parse_args(argv)
    try:
        device = resolve_device(args.device)
    except ValueError as exc:
        print(f'bench_gpu: error: {exc}', file=sys.stderr)
        return 2
    views = args.views or ([2, 4] if args.quick else [8, 16, 32, 64])
    iterations = args.iterations or (3 if args.quick else 30)
    warm_up = 1 if args.quick else 5
    train_views = args.train_views or (2 if args.quick else 8)
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    rng = np.random.default_rng(0)

    model, bev = load_model(shipped_checkpoint(args.checkpoint))
    jpegs, homographies, area, source = source_frames(args.sample, list(MATRIX_AREA), rng)
    grid = bev.grid(area)
    input_size = (bev.image_width, bev.image_height)
    fh_cameras = [feat_H_grid(H, grid.ground_H_grid, FULL_SIZE, input_size, model.stride) for H in homographies]
    prepare_ms = []
    for _ in range(warm_up + iterations):
        t0 = time.perf_counter()
        prepared = [prepare(j, input_size) for j in jpegs]
        prepare_ms.append(1e3 * (time.perf_counter() - t0) / len(jpegs))
    per_view = median(prepare_ms[warm_up:])

    model = model.to(device)
    name = (
        torch.cuda.get_device_name(device)
        if device.type == 'cuda'
        else f'CPU, {torch.get_num_threads()} torch thread(s)'
    )
    rows = []
    for n in views:
        t = bench_views(n, prepared, fh_cameras, bev, model, device, grid, iterations, warm_up)
        fuse = t['upload'] + t['network'] + t['decode']
        rows += [
            ('prepare (CPU, 1 thread)', n, per_view * n, '', f'{per_view:.1f} ms a view, {len(jpegs)} views timed'),
            ('copy to device', n, t['upload'], '', 'the frame\'s network inputs, once'),
            ('lifting', n, t['lifting'], '', 'new taps of every view + gather + pooling (inside the network)'),
            ('network', n, t['network'], '', 'encoder, lifting, aggregation, temporal, heatmap'),
            ('decoding', n, t['decode'], '', 'peaks, heads at the peaks, metres'),
            ('fuse network total', n, fuse, f'{1e3 / fuse:.1f}', 'copy + network + decoding'),
        ]
    train_ms = bench_training(bev, grid, prepared, fh_cameras, train_views, device, iterations, warm_up, rng)
    rows.append(('training step', train_views, train_ms, f'{1e3 / train_ms:.2f}', 'batch 1, AdamW; steps/s'))
    eq = equality(prepared, fh_cameras, bev, device, grid, 2 if args.quick else 3)
    verdict = 'ok' if eq['logit'] <= 1e-3 and eq['position'] <= 1e-3 else 'DIFFERENT'
    rows.append(
        (
            'CPU-device equality',
            len(prepared),
            float('nan'),
            '',
            f'{verdict}: largest logit difference {eq["logit"]:.2e}, '
            f'largest position difference {eq["position"]:.2e} m, '
            f'{eq["detections"]} detections' + (' (the device is the CPU)' if device.type == 'cpu' else ''),
        )
    )

    print(
        f'device: {name} ({device}); torch {torch.__version__}; checkpoint {args.checkpoint}; network input '
        f'{input_size[0]}x{input_size[1]} from {FULL_SIZE[0]}x{FULL_SIZE[1]} JPEG; grid {grid.shape[0]}x'
        f'{grid.shape[1]} cells; frames: {source}; medians of {iterations} frames after {warm_up} warm-up'
    )
    print()
    print('| stage | views | ms per frame | per second | note |')
    print('| --- | ---: | ---: | ---: | --- |')
    for stage, n, ms, rate, note in rows:
        print(f'| {stage} | {n} | {"" if ms != ms else f"{ms:.1f}"} | {rate} | {note} |')
    return 0 if verdict == 'ok' else 1


if __name__ == '__main__':
    sys.exit(main())
