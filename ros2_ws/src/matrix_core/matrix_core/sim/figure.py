"""Side-by-side picture: real MATRIX frames next to simulated views of the same drones.

``python -m matrix_core.sim.figure REAL_MATRIX_DIR OUT.png [--config simple complex modified] [--seed 0]``
writes a PNG with the real images of drones D1, D4 (frame 2) in the left column and the simulator's D1, D4 of
each variant (1920x1080, after 1 s, randomised looks as configured) in the next columns, each 480x270.
"""

import argparse
from pathlib import Path

import cv2
import numpy as np

from matrix_core.datasets import open_dataset
from matrix_core.sim.config import load_scene_config
from matrix_core.sim.sequence import Simulation


def _label(img, text):
    cv2.rectangle(img, (0, 0), (12 + 11 * len(text), 40), (0, 0, 0), -1)
    cv2.putText(img, text, (8, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def sim_vs_real(
    real_dir, out_png, configs=('simple', 'complex', 'modified'), seed=0, views=('D1', 'D4'), frame=2, size=(480, 270)
) -> Path:
    real = open_dataset(real_dir)
    sims = []
    for config in configs:
        sim = Simulation(load_scene_config(config), seed, 1920, 1080)
        sim.step(1.0)
        sims.append((config, sim))
    rows = []
    for view in views:
        tiles = [
            _label(
                cv2.resize(real.load_image(view, frame), size, interpolation=cv2.INTER_AREA),
                f'real MATRIX {view} frame {frame}',
            )
        ]
        for config, sim in sims:
            _, s, _, _ = sim.render_view(sim.views.index(view))
            tiles.append(
                _label(cv2.resize(s, size, interpolation=cv2.INTER_AREA), f'sim {config} {view} (seed {seed})')
            )
        rows.append(np.hstack(tiles))
    out = Path(out_png)
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), np.vstack(rows))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('real_dir')
    p.add_argument('out_png')
    p.add_argument('--config', nargs='+', default=['simple', 'complex', 'modified'])
    p.add_argument('--seed', type=int, default=0)
    a = p.parse_args(argv)
    print(sim_vs_real(a.real_dir, a.out_png, a.config, a.seed))


if __name__ == '__main__':
    main()
