#!/usr/bin/env python3
"""Where one fuse step spends its CPU time, in this process on one thread (run it under ``taskset -c 0``): the
real MATRIX sample's 8 JPEG views (1920x1080, the files' bytes as CompressedImage messages) through the fuse
node's own stages, CPU time per frame (time.process_time, median over ``--frames`` after one warm-up):

    taskset -c 0 python scripts/profile_fuse.py [--frames 10] [--ops 12]

Stages: view inputs (ViewInputs: homography message + JPEG decoded at the reduced scale), network inputs
(resize + normalise, feat_H_grid), the network as the fuser runs it (bev.frame_network) and, for comparison,
BevFusionNet.forward, peaks + heads at peaks + decode, the tracker, and the output messages. Then the
network's most expensive operators (torch.profiler, self CPU time).
"""

import argparse
import os
import time
from pathlib import Path

import cv2
import numpy as np
import torch
from matrix_msgs.msg import HomographyStamped
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from matrix_core.bev.checkpoint import load_model
from matrix_core.bev.decode import find_peaks, peak_detections
from matrix_core.datasets import open_dataset
from matrix_core.fusion.fuser import BevFuser
from matrix_core.fusion.settings import FuseSettings, shipped_checkpoint
from matrix_core.fusion.view_inputs import ViewInputs
from matrix_ros import fusion_messages as out

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument(
        '--dataset', default=os.path.join(os.environ.get('MATRIX_SHARED', ROOT.parent / 'shared'), 'matrix_sample')
    )
    p.add_argument('--frames', type=int, default=10, help='timed frames (the sample\'s 5 cycled)')
    p.add_argument('--ops', type=int, default=12, help='operators listed from the profiler')
    args = p.parse_args()
    dataset = open_dataset(args.dataset)
    settings = FuseSettings(views=list(dataset.views), area=list(map(float, dataset.area)))
    fuser = BevFuser(settings)  # one torch and OpenCV thread, as the node
    model, bev = load_model(shipped_checkpoint())
    runner, grid = fuser.runner, fuser.grid
    inputs = ViewInputs(fuser.input_size, settings.min_confidence, reduced_decode=True)
    messages = []
    for f in dataset.frames:
        frame = {}
        for v in dataset.views:
            H = np.linalg.inv(dataset.camera(v, f).img_H_ground())  # the message holds ground_H_img
            geometry = HomographyStamped(
                status=HomographyStamped.OK, confidence=1.0, h_img_to_ground=(H / H[2, 2]).ravel().tolist()
            )
            data = dataset.image_path(v, f).read_bytes()
            frame[v] = (CompressedImage(format='jpeg', data=data), geometry)
        messages.append(frame)
    for v, (image, geometry) in messages[0].items():  # the first full decode tells each view's size
        inputs.view_input(v, image, geometry, 'homography')
    times, header = {}, Header(frame_id='world')

    def timed(name, fn, *a):
        t = time.process_time()
        result = fn(*a)
        times.setdefault(name, []).append(time.process_time() - t)
        return result

    for k in range(args.frames + 1):
        frame = messages[k % len(messages)]
        views = timed(
            'view inputs (decode 1/r)', lambda: {v: inputs.view_input(v, *m, 'homography') for v, m in frame.items()}
        )
        x = timed('network inputs', lambda: [fuser._view_tensors(views[v]) for v in settings.views])
        images = torch.from_numpy(np.stack([i for i, _ in x]))
        fhs = torch.from_numpy(np.stack([h for _, h in x]).astype(np.float32))
        mask = torch.ones(len(settings.views), dtype=torch.bool)
        previous = runner.previous
        result = timed('network (FrameNetwork)', runner.network, images, fhs, mask, previous)
        with torch.no_grad():
            timed('network (BevFusionNet.forward)', model, images[None], fhs[None], mask[None], grid.shape, previous)
        runner.previous = result.carry

        def decode():
            peaks = find_peaks(result.heatmap, grid, bev.score_threshold, bev.nms_radius_m, bev.max_detections)
            tracking, _ = runner.network.heads_at(result.fused, peaks.rows, peaks.cols)
            return peak_detections(peaks, grid, tracking, None, bev.subcell)

        dets = timed('peaks + heads at peaks + decode', decode)
        tracks = timed('tracker', fuser._track, dets)
        timed(
            'messages (tracks, detections, markers, heatmap)',
            lambda: (
                out.tracks_msg(header, tracks),
                out.detections_msg(header, dets, settings.frame_interval_s),
                out.markers_msg(header, tracks),
                out.heatmap_msg(header, grid, torch.sigmoid(result.heatmap[0]).numpy()),
            ),
        )
    print(
        f'one fuse step on one thread, CPU time per frame (median of {args.frames}; torch threads '
        f'{torch.get_num_threads()}, OpenCV threads {cv2.getNumThreads()}), {len(settings.views)} views 1920x1080 '
        f'JPEG -> {fuser.input_size[0]}x{fuser.input_size[1]}, grid {grid.shape[1]}x{grid.shape[0]}:'
    )
    for name, t in times.items():
        print(f'  {name:50s} {1000 * np.median(t[1:]):7.1f} ms')
    steps = [n for n in times if n != 'network (BevFusionNet.forward)']
    total = sum(np.median(times[n][1:]) for n in steps)
    print(f'  {"total (without BevFusionNet.forward)":50s} {1000 * total:7.1f} ms -> {1 / total:.2f} frames/s')
    with torch.profiler.profile(activities=[torch.profiler.ProfilerActivity.CPU], record_shapes=True) as prof:
        runner.network(images, fhs, mask, runner.previous)
    print(prof.key_averages(group_by_input_shape=True).table(sort_by='self_cpu_time_total', row_limit=args.ops))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
