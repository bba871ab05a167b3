"""Report of the detector recipe: every seed's checkpoint on held-out simulated test sequences and on
the real MATRIX sample, as a table (stdout, ``report.md``), ``report.json`` and a PNG of real-frame heatmaps.

Rows per checkpoint (see docs/detector.md for the protocol):
  sim complex test  data/det_complex_test_s201 (simulator seed 201, 60 frames; test: never used for selection)
  sim modified test data/det_modified_test_s202 (seed 202, 60 frames; test)
  real, true calib  ../shared/matrix_sample frames 0-4 with the dataset's per-frame calibration (VALIDATION:
                    checkpoints are selected on these frames, so they are no test accuracy)
  real, registered  the same frames with the registration homographies of ``matrix-tracker register`` (what
                    the live graph fuses; VALIDATION as well)
``corner fp`` counts detections within 2 m of a corner of the area that match no person (the real scene's
posts with spheres stand there).

``validation.png`` draws each seed's validation MODA per sequence and epoch from the training history beside its
checkpoint (``detector_seedN.history.json``), with the weight average of the last epochs as stars and the
exported (selected) model in the title.

Usage: python scripts/detector_report.py [--checkpoints A.pt B.pt ...] [--out out/detector_report]
(default: every matrix_core/bev/checkpoints/detector_seed*.pt). Data: bash scripts/detector_data.sh test.
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

os.environ.setdefault('OMP_NUM_THREADS', '1')

import numpy as np  # noqa: E402
import torch  # noqa: E402

import matrix_core.bev  # noqa: E402
from matrix_core.bev.checkpoint import load_checkpoint, load_model  # noqa: E402
from matrix_core.bev.data import BevFrames  # noqa: E402
from matrix_core.bev.evaluation import evaluate  # noqa: E402

CHECKPOINTS = Path(matrix_core.bev.__file__).parent / 'checkpoints'
SHARED = Path(os.environ.get('MATRIX_SHARED', Path(__file__).resolve().parents[1].parent / 'shared'))
CORNER_RADIUS_M = 2.0
COLUMNS = ('MODA', 'MODP', 'prec', 'rec', 'MOTA', 'MOTP', 'IDF1', 'MT %', 'ML %', 'IDsw', 'corner fp')


def rows(real_registration: Path) -> list:
    """(name, folder, calibration source, calibration dir) of every evaluated row."""
    sample = SHARED / 'matrix_sample'
    return [
        ('sim complex test s201', Path('data/det_complex_test_s201'), 'ground_truth', None),
        ('sim modified test s202', Path('data/det_modified_test_s202'), 'ground_truth', None),
        ('real 0-4, true calib (val)', sample, 'ground_truth', None),
        ('real 0-4, registration (val)', sample, 'registration', real_registration),
    ]


def corner_false_positives(result, area) -> int:
    """Detections within CORNER_RADIUS_M of an area corner with no ground-truth person within 0.5 m."""
    x0, y0, x1, y1 = area
    corners = np.array([[x0, y0], [x0, y1], [x1, y0], [x1, y1]])
    count = 0
    for frame, xy in zip(result.detections.frames, result.detections.xy):
        near_corner = np.linalg.norm(corners - xy, axis=1).min() < CORNER_RADIUS_M
        gt = result.gt.xy[result.gt.frames == frame]
        if near_corner and (len(gt) == 0 or np.linalg.norm(gt - xy, axis=1).min() > 0.5):
            count += 1
    return count


def figures(result, area) -> dict:
    d, t = result.detection, result.tracking
    ids = max(t.num_gt_ids, 1)
    return {
        'MODA': 100 * d.moda,
        'MODP': 100 * d.modp,
        'prec': 100 * d.precision,
        'rec': 100 * d.recall,
        'MOTA': 100 * t.mota,
        'MOTP': t.motp_percent,
        'IDF1': 100 * t.idf1,
        'MT %': 100 * t.mostly_tracked / ids,
        'ML %': 100 * t.mostly_lost / ids,
        'IDsw': t.id_switches,
        'corner fp': corner_false_positives(result, area),
    }


def ensure_registration(out: Path) -> Path:
    """Registration homographies of the real sample (``matrix-tracker register``), computed once."""
    reg = out / 'real_registration'
    if not (reg / 'summary.json').is_file():
        subprocess.run(['matrix-tracker', 'register', str(SHARED / 'matrix_sample'), '--out', str(reg)], check=True)
    return reg


def heatmap_png(path: Path, panels: list, grid) -> None:
    """One real frame's heatmap per checkpoint, ground truth (o) and detections (x)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 5.2), dpi=100, squeeze=False)
    for ax, (title, output, gt) in zip(axes[0], panels):
        ax.imshow(
            output.heatmap,
            origin='lower',
            extent=(grid.x_min, grid.x_max, grid.y_min, grid.y_max),
            cmap='magma',
            vmin=0,
            vmax=1,
        )
        ax.scatter(gt[:, 0], gt[:, 1], s=40, facecolors='none', edgecolors='lime', label='ground truth')
        det = output.detections.xy
        ax.scatter(det[:, 0], det[:, 1], s=25, marker='x', c='red', label='detections')
        ax.set_title(title, fontsize=9)
        ax.set_xlabel('x (m)')
    axes[0][0].set_ylabel('y (m)')
    axes[0][0].legend(loc='upper right', fontsize=7)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches='tight')
    plt.close(fig)


def validation_png(path: Path, checkpoints: list) -> bool:
    """Validation MODA per sequence over the epochs of each checkpoint's training history (``X.history.json``
    beside ``X.pt``), one panel per checkpoint, the weight average (if any) as stars after the last epoch.
    False when no checkpoint has a history with per-sequence validation (histories before it was logged)."""
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    panels = []
    for ckpt in checkpoints:
        history_path = ckpt.with_suffix('.history.json')
        if not history_path.is_file():
            continue
        records = [h for h in json.loads(history_path.read_text()) if 'val_score' in h]
        history = [h for h in records if 'averaged' not in h]
        averaged = [h for h in records if 'averaged' in h]
        labels = sorted({k[len('val_moda[') : -1] for h in history for k in h if k.startswith('val_moda[')})
        if history and labels:
            shipped = load_checkpoint(ckpt)
            chosen = (
                f'average of epochs {shipped["averaged"][0]}-{shipped["averaged"][-1]}'
                if 'averaged' in shipped
                else f'epoch {shipped.get("epoch")}'
            )
            panels.append((ckpt.stem, history, labels, averaged[-1] if averaged else None, chosen))
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 3.8), dpi=100, squeeze=False, sharey=True)
    for ax, (name, history, labels, averaged, chosen) in zip(axes[0], panels):
        epochs = [h['epoch'] for h in history]
        for k, label in enumerate(labels):
            colour = f'C{k}'
            ax.plot(
                epochs,
                [100 * h.get(f'val_moda[{label}]', np.nan) for h in history],
                marker='o',
                color=colour,
                label=label,
            )
            if averaged is not None:  # the weight average, drawn half an epoch after the last
                ax.plot(epochs[-1] + 0.5, 100 * averaged.get(f'val_moda[{label}]', np.nan), '*', ms=12, color=colour)
        ax.plot(epochs, [100 * h['val_score'] for h in history], 'k-', lw=2, label='val_score (selects)')
        if averaged is not None:
            ax.plot(
                epochs[-1] + 0.5,
                100 * averaged['val_score'],
                'k*',
                ms=14,
                label=f'average of epochs {averaged["averaged"][0]}-{averaged["averaged"][-1]} (*)',
            )
        ax.set_title(f'{name}: exported {chosen}', fontsize=9)
        ax.set_xlabel('epoch')
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel('validation MODA (%)')
    axes[0][0].legend(fontsize=7, loc='lower right')
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches='tight')
    plt.close(fig)
    return True


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--checkpoints', nargs='*', type=Path, default=sorted(CHECKPOINTS.glob('detector_seed*.pt')))
    p.add_argument('--out', type=Path, default=Path('out/detector_report'))
    p.add_argument('--frame', type=int, default=2, help='real frame drawn in heatmaps.png')
    args = p.parse_args(argv)
    if not args.checkpoints:
        sys.exit('no checkpoints (train first: bash scripts/train_detector.sh 0 1 2)')
    torch.set_num_threads(1)
    args.out.mkdir(parents=True, exist_ok=True)
    table, panels, grid = {}, [], None
    for ckpt in args.checkpoints:
        model, settings = load_model(ckpt)
        for name, folder, source, cdir in rows(ensure_registration(args.out)):
            if not folder.is_dir():
                print(f'skip {name}: {folder} missing (bash scripts/detector_data.sh test)', file=sys.stderr)
                continue
            data = BevFrames(folder, settings, calibration=source, cache_images=False, calibration_dir=cdir)
            result = evaluate(model, data, progress=False)
            table[(ckpt.stem, name)] = figures(result, data.dataset.area)
            print(
                f'{ckpt.stem:18s} {name:30s} ' + ' '.join(f'{k} {v:.1f}' for k, v in table[(ckpt.stem, name)].items()),
                flush=True,
            )
            if source == 'ground_truth' and folder == SHARED / 'matrix_sample':
                output = next(o for o in result.outputs if o.frame == args.frame)
                panels.append(
                    (f'{ckpt.stem}: real frame {args.frame}', output, result.gt.xy[result.gt.frames == args.frame])
                )
                grid = data.grid
    head = '| checkpoint | data | ' + ' | '.join(COLUMNS) + ' |'
    lines = [head, '|' + '---|' * (len(COLUMNS) + 2)]
    for (ckpt, name), f in table.items():
        lines.append(
            f'| {ckpt} | {name} | '
            + ' | '.join(f'{f[c]:.1f}' if isinstance(f[c], float) else str(f[c]) for c in COLUMNS)
            + ' |'
        )
    text = '\n'.join(lines)
    print(text)
    (args.out / 'report.md').write_text(text + '\n')
    (args.out / 'report.json').write_text(
        json.dumps([{'checkpoint': c, 'data': n, **f} for (c, n), f in table.items()], indent=1)
    )
    if panels:
        heatmap_png(args.out / 'heatmaps.png', panels, grid)
    curves = validation_png(args.out / 'validation.png', args.checkpoints)
    print(f'wrote {args.out}/report.md, report.json, heatmaps.png' + (', validation.png' if curves else ''))
    return 0


if __name__ == '__main__':
    sys.exit(main())
