"""``matrix-tracker simulate``: generate a seeded MATRIX-like sequence (folder + optional rosbag2)."""

from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.sim.settings import SimulateSettings


def add_parser(subparsers) -> None:
    p = subparsers.add_parser('simulate', help='generate a seeded MATRIX-like scene sequence (and a bag)',
                              description=__doc__)
    add_settings_arguments(p, SimulateSettings)
    p.set_defaults(func=run)


def run(args) -> int:
    from matrix_core.sim.sequence import simulate

    settings = settings_from_namespace(SimulateSettings, args)
    out = simulate(settings)
    print(f'wrote {settings.frames} frames of {settings.config} (seed {settings.seed}, '
          f'{settings.width}x{settings.height}) to {out}')
    return 0
