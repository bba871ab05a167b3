"""``matrix-tracker train --config CONFIG``: train the BEV fusion network on MATRIX-format folders or site datasets;
``matrix-tracker train --site SITE``: a detector for one site, on sequences of it that it simulates itself
(``cli/train_site.py``, docs/your-own-site.md).

CONFIG is a YAML file or the name of a shipped config (``matrix_core/bev/configs``: sample, complex).
Writes ``last.pt`` (every epoch, for --resume), ``best.pt`` (best validation score, ``val_score``: MODA
weighted per validation sequence) and ``history.json`` (per epoch: losses, each validation sequence's MODA, MOTA, IDF1).
``--device`` (``auto`` | ``cpu`` | ``cuda`` | ``cuda:N``, ``matrix_core.device``): where the network trains; a GPU
this machine lacks is an error before anything is read.
"""

from matrix_core.cli.argument_types import non_negative_int, positive_int
from matrix_core.cli.train_site import add_site_arguments, run_site
from matrix_core.device import DeviceSettings
from matrix_core.output_paths import add_overwrite_argument, check_output
from matrix_core.settings import add_settings_arguments, settings_from_namespace


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'train', help='train the BEV fusion network (progress bars, checkpoints, resume)', description=__doc__
    )
    p.add_argument('--config', help='YAML config file or shipped config name (required without --site)')
    p.add_argument('--out', help='output folder (default: out_dir of the config)')
    p.add_argument('--resume', action='store_true', help='continue from OUT/last.pt if it exists')
    add_overwrite_argument(p)
    p.add_argument('--epochs', type=positive_int, help='override the number of epochs')
    p.add_argument('--max-steps-per-epoch', type=non_negative_int, help='override max_steps_per_epoch (0: all)')
    p.add_argument('--seed', type=int, help='override the seed')
    p.add_argument(
        '--export',
        metavar='PATH',
        help='after training, write last.pt without the optimizer state '
        'to PATH (how the shipped checkpoints/*.pt are made; with --resume on a finished run it '
        'only exports)',
    )
    p.add_argument(
        '--export-from',
        choices=('last', 'best'),
        default='last',
        help='which checkpoint --export writes: the last epoch, or best.pt (highest validation score '
        'val_score: the model-selection protocol of the shipped default, docs/detector.md)',
    )
    add_settings_arguments(p, DeviceSettings)
    add_site_arguments(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from matrix_core.bev.config import CONFIG_DIR, load_config, resolve_config_path
    from matrix_core.bev.training import train

    device = settings_from_namespace(DeviceSettings, args).device  # a GPU this machine lacks: an error now
    overrides = {
        k: v
        for k, v in (('epochs', args.epochs), ('max_steps_per_epoch', args.max_steps_per_epoch), ('seed', args.seed))
        if v is not None
    }
    if args.site:
        return run_site(args, device, overrides)
    if not args.config:
        raise ValueError('--config is required (or --site SITE: a detector for that site)')
    config = load_config(args.config, overrides)
    out = Path(args.out or config.out_dir)
    # before any work: never into a training or validation sequence or over the config; an earlier run's
    # folder only with --resume (continue it) or --overwrite
    inputs = [resolve_config_path(args.config), *(s.path for s in [*config.train, *config.val])]
    check_output(out, inputs, args.resume or args.overwrite)
    if args.export:  # a shipped checkpoint is re-exported in place: only an overlap with an input is refused
        check_output(args.export, inputs, True, '--export')
    history = train(config, args.out, resume=args.resume, device=device)
    epochs = [h for h in history if 'averaged' not in h]
    averaged = ' and the weight average of the last ones' if len(epochs) < len(history) else ''
    print(f'done: {len(epochs)} epochs{averaged}, checkpoints in {out}')
    if args.export:
        from matrix_core.bev.checkpoint import export_checkpoint

        cfg = resolve_config_path(args.config)
        source = out / f'{args.export_from}.pt'
        if not source.is_file():
            raise FileNotFoundError(
                f'--export-from {args.export_from}: {source} was not written '
                '(best.pt needs validation sequences in the config)'
            )
        recipe = f'configs/{cfg.name}' if cfg.parent == CONFIG_DIR else str(cfg)
        path = export_checkpoint(
            source, args.export, trained_with=f'{recipe} --seed {config.seed} ({args.export_from}.pt)'
        )
        print(f'exported {path} ({path.stat().st_size / 1e6:.1f} MB)')
    return 0
