"""Benchmark of the simulator renderer: frames (8 views) per second for a scene variant, on ONE core.

Usage: python scripts/bench_sim.py [--config complex] [--frames 20]
Prints frames/s and views/s at 640x360 and 1920x1080 (render + line of sight + annotation boxes; no file
writing). Target: >= 5 frames/s (40 views/s) at 640x360.
"""

import argparse
import os
import time

os.environ.setdefault('OMP_NUM_THREADS', '1')

import cv2  # noqa: E402

from matrix_core.sim.config import load_scene_config  # noqa: E402
from matrix_core.sim.ground_truth import annotation_box  # noqa: E402
from matrix_core.sim.sequence import Simulation  # noqa: E402


def bench(config, width, height, frames):
    t0 = time.perf_counter()
    sim = Simulation(config, seed=0, width=width, height=height)
    setup = time.perf_counter() - t0
    render_s = 0.0
    for _ in range(frames):
        sim.step(0.5)
        t = time.perf_counter()
        for k in range(len(sim.views)):
            cam, _, _, visible = sim.render_view(k)
            for xy in sim.crowd.positions[visible]:
                annotation_box(cam, xy)
        render_s += time.perf_counter() - t
    return setup, frames / render_s, frames * len(sim.views) / render_s


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--config', default='complex')
    parser.add_argument('--frames', type=int, default=20)
    args = parser.parse_args()
    cv2.setNumThreads(1)
    config = load_scene_config(args.config)
    for width, height in ((640, 360), (1920, 1080)):
        setup, fps, vps = bench(config, width, height, args.frames)
        print(
            f'sim {args.config} {width}x{height}: {fps:.1f} frames/s ({vps:.0f} views/s, 8 views/frame, '
            f'1 thread); scene setup {setup:.2f} s'
        )


if __name__ == '__main__':
    main()
