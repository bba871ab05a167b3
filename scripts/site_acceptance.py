#!/usr/bin/env python3
"""The figures of a site, by the path of docs/your-own-site.md: one table row and the commands that made it.

For a site file (a path or a shipped site: plaza, ring3, ring12) and a detector checkpoint:

1. ``matrix-tracker simulate --site SITE --seed SEED --bag``: a held-out recording (``--frames`` frames at
   ``--image-scale`` of the site's image size) with its ground truth; the default seed is none of
   ``train --site``'s default training and validation seeds (printed);
2. ``matrix-tracker site init`` from that bag and the site's boards (step 3 of the tutorial);
3. ``ros2 launch matrix_bringup full_graph.launch.py bag:=... site:=... checkpoint:=... record:=... monitor:=true
   monitor_out:=...`` (step 6 of the tutorial): the whole graph on the bag with the site ``site init`` wrote,
   the checkpoint, the recorder and the graph monitor, to its end; a non-zero exit status stops the script;
4. ``matrix-tracker evaluate-recording`` of the recorded tracks against the bag's ground truth.

It prints the commands as it runs them, then one row: site, drones, frames, image scale, the checkpoint's file
name, the median calibration error (deg) and the median registration error (reference pixels) of the graph
monitor (``graph_scores.csv``), and MODA, MOTA and IDF1 (%) of the recording. Everything goes under ``--out``
(default out/site_acceptance/SITE); an existing folder is replaced.

    source scripts/env.sh
    nice -n 19 python scripts/site_acceptance.py --site ring3 --checkpoint detector_tiny_seed0.pt \\
        --frames 6 --image-scale 0.5
    python scripts/site_acceptance.py --site plaza --checkpoint out/train/plaza/detector_plaza.pt --frames 100
"""

import argparse
import csv
import json
import shlex
import shutil
import statistics
import subprocess
import sys
from pathlib import Path

import yaml

from matrix_core.cli.train_site import DEFAULT_TRAIN_SEEDS, DEFAULT_VAL_SEEDS
from matrix_core.site import load_site
from matrix_core.site.shipped import site_path

HELD_OUT_SEED = 201
BOARD_KEYS = ('name', 'area', 'cell_m', 'boards', 'obstacles')  # a boards description: the site file without drones


def _ros2() -> str:
    if not shutil.which('ros2'):
        raise SystemExit('ros2 not found: run make setup, then source scripts/env.sh')
    return 'ros2'


def _run(cmd: list, commands: list, log: Path) -> None:
    """Run ``cmd`` (its output to ``log``), note it in ``commands``; exit naming the log when it fails."""
    text = shlex.join(str(c) for c in cmd)
    commands.append(text)
    print(f'$ {text}', flush=True)
    with open(log, 'w') as f:
        rc = subprocess.run([str(c) for c in cmd], stdout=f, stderr=subprocess.STDOUT).returncode
    if rc:
        sys.exit(f'failed (exit code {rc}): {text}\n{log.read_text()[-3000:]}')


def _median(rows: list, column: str):
    values = [float(r[column]) for r in rows if r[column] not in ('', 'None')]
    return statistics.median(values) if values else float('nan')


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument('--site', required=True, help='site file: a path or a shipped site (plaza, ring3, ring12)')
    p.add_argument('--checkpoint', required=True, help='detector checkpoint: a path or a shipped name')
    p.add_argument('--frames', type=int, default=100, help='frames of the held-out recording')
    p.add_argument('--seed', type=int, default=HELD_OUT_SEED, help='seed of the held-out recording')
    p.add_argument('--image-scale', type=float, default=1.0, help="fraction of the site's image size")
    p.add_argument('--sim-config', default='complex', help="simulate's --config (crowd, light, distractors)")
    p.add_argument(
        '--lockstep-timeout', type=float, help="the launch's lockstep_timeout:=, s (default: not given, the launch's)"
    )
    p.add_argument('--out', help='output folder (default out/site_acceptance/<site name>)')
    args = p.parse_args(argv)

    site_file = site_path(args.site)
    site = load_site(site_file)
    out = Path(args.out or f'out/site_acceptance/{site.name}').resolve()
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    used = sorted({*DEFAULT_TRAIN_SEEDS, *DEFAULT_VAL_SEEDS})
    note = 'not used' if args.seed not in used else 'USED'
    print(f'held-out seed {args.seed} ({note} by train --site defaults: training and validation seeds {used})')
    flight, site_dir, rec, monitor = out / 'flight', out / 'site', out / 'rec', out / 'monitor'
    boards = out / 'boards.yaml'
    raw = yaml.safe_load(site_file.read_text())
    boards.write_text(yaml.safe_dump({k: raw[k] for k in BOARD_KEYS if k in raw}, sort_keys=False))
    commands = []
    simulate = ['matrix-tracker', 'simulate', '--site', args.site, '--config', args.sim_config]
    simulate += ['--frames', args.frames, '--seed', args.seed, '--image_scale', args.image_scale]
    _run([*simulate, '--out', flight, '--bag'], commands, out / 'simulate.log')
    _run(
        ['matrix-tracker', 'site', 'init', '--bag', flight / 'bag', '--boards', boards, '--out', site_dir],
        commands,
        out / 'site_init.log',
    )
    checkpoint = Path(args.checkpoint).resolve() if Path(args.checkpoint).is_file() else args.checkpoint
    graph = [_ros2(), 'launch', 'matrix_bringup', 'full_graph.launch.py', f'bag:={flight / "bag"}']
    graph += [f'site:={site_dir / "site.yaml"}', f'checkpoint:={checkpoint}', f'record:={rec}']
    graph += ['monitor:=true', f'monitor_out:={monitor}']
    if args.lockstep_timeout is not None:
        graph.append(f'lockstep_timeout:={args.lockstep_timeout}')
    _run(graph, commands, out / 'launch.log')
    metrics = out / 'recording_metrics.json'
    score = ['matrix-tracker', 'evaluate-recording', rec, '--ground-truth', flight / 'bag', '--json', metrics]
    _run(score, commands, out / 'evaluate_recording.log')

    with open(monitor / 'graph_scores.csv') as f:
        rows = list(csv.DictReader(f))
    result = json.loads(metrics.read_text())
    drones = len(load_site(site_dir / 'site.yaml').drone_names)
    figures = {
        'site': site.name,
        'drones': f'{drones}/{len(site.drone_names)}',
        'frames': args.frames,
        'image scale': args.image_scale,
        'checkpoint': f'`{Path(args.checkpoint).name}`',
        'calib_deg': f'{_median(rows, "rot_err_deg"):.3f}',
        'reg_px': f'{_median(rows, "reg_ref_err_px"):.2f}',
        'MODA': f'{100 * result["detection"]["moda"]:.1f}',
        'MOTA': f'{100 * result["tracking"]["mota"]:.1f}' if result['tracking'] else '-',
        'IDF1': f'{100 * result["tracking"]["idf1"]:.1f}' if result['tracking'] else '-',
    }
    print('\ncommands:\n' + '\n'.join(commands))
    print(f'\n(seed {args.seed}, image scale {args.image_scale}, sim config {args.sim_config}; drones: in site init\'s')
    print('site / in the site file; calib_deg, reg_px: medians over every drone frame of graph_monitor)')
    print('| ' + ' | '.join(figures) + ' |')
    print('| ' + ' | '.join(str(v) for v in figures.values()) + ' |')
    (out / 'row.json').write_text(json.dumps({**figures, 'seed': args.seed, 'commands': commands}, indent=2))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
