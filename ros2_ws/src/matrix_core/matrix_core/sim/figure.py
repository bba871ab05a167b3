"""Side-by-side picture: real MATRIX frames next to simulated views of the same drones.

``python -m matrix_core.sim.figure REAL_MATRIX_DIR OUT.png [--config complex] [--seed 0]`` writes a PNG with
the real images of drones D1, D4 (frame 2) in the left column and the simulator's D1, D4 (complex, 1920x1080,
after 1 s) in the right column, each downscaled to 640x360.
"""

import argparse
from pathlib import Path

import cv2
import numpy as np

from matrix_core.datasets import open_dataset
from matrix_core.sim.config import load_scene_config
from matrix_core.sim.sequence import Simulation


def _label(img, text):
    cv2.rectangle(img, (0, 0), (12 + 12 * len(text), 40), (0, 0, 0), -1)
    cv2.putText(img, text, (8, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def sim_vs_real(real_dir, out_png, config='complex', seed=0, views=('D1', 'D4'), frame=2) -> Path:
    real = open_dataset(real_dir)
    sim = Simulation(load_scene_config(config), seed, 1920, 1080)
    sim.step(1.0)
    rows = []
    for view in views:
        r = cv2.resize(real.load_image(view, frame), (640, 360), interpolation=cv2.INTER_AREA)
        _, s, _, _ = sim.render_view(sim.views.index(view))
        s = cv2.resize(s, (640, 360), interpolation=cv2.INTER_AREA)
        rows.append(np.hstack([_label(r, f'real MATRIX {view} frame {frame}'),
                               _label(s, f'simulated {config} {view} (seed {seed})')]))
    out = Path(out_png)
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), np.vstack(rows))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('real_dir')
    p.add_argument('out_png')
    p.add_argument('--config', default='complex')
    p.add_argument('--seed', type=int, default=0)
    a = p.parse_args(argv)
    print(sim_vs_real(a.real_dir, a.out_png, a.config, a.seed))


if __name__ == '__main__':
    main()
