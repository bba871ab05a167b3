"""``matrix-tracker train --config CONFIG``: train the BEV fusion network on MATRIX-format folders.

CONFIG is a YAML file or the name of a shipped config (``matrix_core/bev/configs``: sample, complex).
Writes ``last.pt`` (every epoch, for --resume), ``best.pt`` (best validation MODA) and ``history.json``.
"""


def add_parser(subparsers) -> None:
    p = subparsers.add_parser('train', help='train the BEV fusion network (progress bars, checkpoints, resume)',
                              description=__doc__)
    p.add_argument('--config', required=True, help='YAML config file or shipped config name')
    p.add_argument('--out', help='output folder (default: out_dir of the config)')
    p.add_argument('--resume', action='store_true', help='continue from OUT/last.pt if it exists')
    p.add_argument('--epochs', type=int, help='override the number of epochs')
    p.add_argument('--max-steps-per-epoch', type=int, help='override max_steps_per_epoch (0: all)')
    p.add_argument('--seed', type=int, help='override the seed')
    p.set_defaults(func=run)


def run(args) -> int:
    from matrix_core.bev.config import load_config
    from matrix_core.bev.training import train

    overrides = {k: v for k, v in (('epochs', args.epochs), ('max_steps_per_epoch', args.max_steps_per_epoch),
                                   ('seed', args.seed)) if v is not None}
    config = load_config(args.config, overrides)
    history = train(config, args.out, resume=args.resume)
    print(f'done: {len(history)} epochs, checkpoints in {args.out or config.out_dir}')
    return 0
