"""``matrix-tracker train --site SITE``: simulate the site's training and validation sequences (or reuse them),
train on them from a checkpoint's weights or from scratch on the site's BEV grid, and export a checkpoint that
records the site (``bev/site_training.py``; docs/your-own-site.md)."""

from pathlib import Path

from matrix_core.cli.argument_types import positive_int
from matrix_core.output_paths import check_output

DEFAULT_RECIPE = 'site'
DEFAULT_TRAIN_SEEDS = (101, 102, 103, 104, 105, 106)
DEFAULT_VAL_SEEDS = (111,)


def add_site_arguments(p) -> None:
    """The flags that apply with ``--site``."""
    from matrix_core.fusion.settings import DEFAULT_CHECKPOINT

    g = p.add_argument_group('train --site SITE (a detector for one site, docs/your-own-site.md)')
    g.add_argument(
        '--site',
        help='site file or shipped site name: simulate its sequences and train on its BEV grid (area, cell); '
        f'--config then defaults to the shipped recipe {DEFAULT_RECIPE!r}, --out to out/train/<site name>, and '
        '--export (default OUT/detector_<site name>.pt) writes best.pt (last.pt without validation seeds)',
    )
    g.add_argument(
        '--init',
        default=DEFAULT_CHECKPOINT,
        help=f'checkpoint to fine-tune (a path or a shipped name, e.g. detector_tiny_seed0.pt; default '
        f'{DEFAULT_CHECKPOINT}), or "scratch": its network is the one trained',
    )
    g.add_argument('--sim-config', default='complex', help='simulator scene variant: crowd, light, distractors')
    g.add_argument(
        '--train-seeds', type=int, nargs='*', default=list(DEFAULT_TRAIN_SEEDS), help='one training sequence each'
    )
    g.add_argument(
        '--val-seeds', type=int, nargs='*', default=list(DEFAULT_VAL_SEEDS), help='one validation sequence each'
    )
    g.add_argument('--frames', type=positive_int, default=60, help='frames per training sequence')
    g.add_argument('--val-frames', type=positive_int, default=30, help='frames per validation sequence')
    g.add_argument(
        '--image-scale', type=float, default=0.5, help='simulated images at this fraction of the site\'s sizes'
    )
    g.add_argument(
        '--train-data',
        nargs='*',
        default=[],
        metavar='DIR',
        help='site datasets of the site to train on as well (simulated beforehand, or your annotated real frames)',
    )
    g.add_argument('--val-data', nargs='*', default=[], metavar='DIR', help='site datasets to validate on as well')
    g.add_argument(
        '--val-data-weight',
        type=float,
        default=1.0,
        help='weight of each --val-data dataset in val_score (the default recipe weighs real frames 2)',
    )
    g.add_argument('--data', help='folder of the simulated sequences (default OUT/data); finished ones are reused')


def run_site(args, device: str, overrides: dict) -> int:
    from matrix_core.bev.checkpoint import export_checkpoint
    from matrix_core.bev.config import load_config, resolve_config_path
    from matrix_core.bev.site_training import (
        SCRATCH,
        init_settings,
        plan_site_training,
        simulate_missing,
        site_bev_settings,
        site_record,
    )
    from matrix_core.bev.training import train
    from matrix_core.site import load_site, site_path
    from matrix_core.site.shipped import MATRIX_SITE

    if args.site == MATRIX_SITE:
        raise ValueError(
            '--site matrix: the MATRIX detector has its own recipe: train --config detector (docs/detector.md)'
        )
    site = load_site(site_path(args.site))
    recipe = args.config or DEFAULT_RECIPE
    init_path, init_bev = init_settings(args.init)
    config = load_config(recipe, overrides)
    out = Path(args.out or f'out/train/{site.name}')
    data = Path(args.data) if args.data else out / 'data'
    plan = plan_site_training(
        site, data, args.train_seeds, args.val_seeds, args.frames, args.val_frames, args.sim_config,
        args.image_scale, args.train_data, args.val_data, args.val_data_weight,
    )  # fmt: skip
    config.train, config.val = plan.specs()
    config.bev = site_bev_settings(config.bev, site, init_bev)
    config.init = str(init_path) if init_path else ''
    export = Path(args.export or out / f'detector_{site.name}.pt')
    # before any work: never into an input (the site, the recipe, the init checkpoint, a given dataset)
    inputs = [site.path, resolve_config_path(recipe), init_path, *args.train_data, *args.val_data]
    check_output(out, inputs, args.resume or args.overwrite)
    check_output(data, inputs, True, '--data')
    check_output(export, inputs, True, '--export')
    for line in plan.summary():
        print(line)
    rows, cols = config.bev.grid().shape
    start = f'fine-tuning {init_path.name}' if init_path else 'from scratch'
    print(
        f'network {config.bev.model} ({start}) on the BEV grid of {site.name}: {rows} x {cols} cells of '
        f'{config.bev.cell_m:g} m over {list(site.area)} plus {config.bev.margin_m:g} m'
    )
    simulate_missing(plan)
    history = train(config, out, resume=args.resume, device=device, tags={'site': site_record(site)})
    epochs = [h for h in history if 'averaged' not in h]
    which = 'best' if config.val else 'last'
    seeds = f'train seeds {plan.seeds("train")}, validation seeds {plan.seeds("val")}'
    trained_with = (
        f'train --site {site.path} --config {recipe} --init {args.init if init_path else SCRATCH} '
        f'--seed {config.seed}; {seeds} ({which}.pt)'
    )
    path = export_checkpoint(out / f'{which}.pt', export, trained_with=trained_with)
    chosen = max((h for h in history if 'val_score' in h), key=lambda h: h['val_score'], default=None)
    if chosen:
        print(f'selected: epoch {chosen["epoch"]}{" (weight average)" if "averaged" in chosen else ""}, '
              f'validation MODA {100 * chosen["val_score"]:.2f} %')  # fmt: skip
    print(f'done: {len(epochs)} epochs; checkpoint for site {site.name}: {path}')
    print(f'  live:    checkpoint:={path.resolve()} (the fuse node; ros2 launch matrix_bringup full_graph.launch.py)')
    print(f'  offline: matrix-tracker evaluate DATASET --checkpoint {path}')
    return 0
