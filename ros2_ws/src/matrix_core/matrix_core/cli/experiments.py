"""``matrix-tracker experiments --mode quick|medium|standard|full``: the MATRIX paper's experiments on
simulated MATRIX variants (simple and complex through the live pipeline, oracle geometry and static
baselines; transfer sweep; camera dropout; run-to-run variation over RANSAC and training seeds; the
dataset readers on the real MultiviewX sample), then ``--report`` (RESULTS.md) and its PNGs.

Everything goes to ``OUT/<mode>/`` (datasets, calibrations, checkpoints, metrics); finished steps are
cached there, so a rerun resumes where the last one stopped. The small per-step files (``run.json``,
``steps/*.done.json`` with each step's commit, every ``metrics.json``) are copied to ``--metrics``
(default ``<report folder>/results/<mode>``, i.e. docs/results/MODE: commit them), and the report is
written from there; ``--report-only`` rewrites the report from that folder alone. ``quick`` (minutes) is a
smoke test; ``standard`` is the size of docs/RESULTS.md (about 2.5 hours with two steps at once on a
2-core machine); ``full`` the shipped complex model's recipe (many hours). ``--device`` (``auto`` | ``cpu`` |
``cuda`` | ``cuda:N``, ``matrix_core.device``): where training and evaluation run the network; a GPU this machine
lacks is an error before the first step.
"""

from matrix_core.cli.argument_types import positive_int
from matrix_core.device import DeviceSettings
from matrix_core.settings import add_settings_arguments, settings_from_namespace


def add_parser(subparsers) -> None:
    from matrix_core.experiments.sizes import SIZES

    p = subparsers.add_parser(
        'experiments', help="run the paper's experiments and write docs/RESULTS.md", description=__doc__
    )
    p.add_argument('--mode', choices=list(SIZES), default='quick', help='run size (default: quick)')
    p.add_argument('--out', default='out/experiments', help='run folder root (the run goes to OUT/MODE)')
    p.add_argument('--report', default='docs/RESULTS.md', help='markdown report to write')
    p.add_argument('--images', help='folder for the PNGs (default: images/results next to the report)')
    p.add_argument(
        '--metrics',
        help='folder of the per-step files the report is written from (default: results/MODE next to the report)',
    )
    p.add_argument('--threads', type=positive_int, default=1, help='torch threads per step (default 1)')
    p.add_argument(
        '--jobs',
        type=positive_int,
        help="steps run at once, one process each (default: the size's, 2 for standard and full, 1 for quick)",
    )
    p.add_argument('--report-only', action='store_true', help='only rewrite the report from the --metrics folder')
    p.add_argument('--no-progress', action='store_true', help='no progress bars')
    add_settings_arguments(p, DeviceSettings)
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from matrix_core.experiments.archive import default_metrics_dir
    from matrix_core.experiments.report import write_report
    from matrix_core.experiments.runner import run_experiments
    from matrix_core.experiments.sizes import SIZES

    device = settings_from_namespace(DeviceSettings, args).device  # a GPU this machine lacks: an error now
    size = SIZES[args.mode]
    metrics = Path(args.metrics) if args.metrics else default_metrics_dir(args.report, size.name)
    if args.report_only:
        path = write_report(metrics, args.report, args.images)
        print(f'wrote {path} from {metrics}')
        return 0
    summary, path = run_experiments(
        size,
        args.out,
        args.report,
        args.images,
        args.threads,
        not args.no_progress,
        jobs=args.jobs,
        metrics_dir=metrics,
        device=device,
    )
    states = [s['state'] for s in summary['steps'].values()]
    counts = ', '.join(f'{states.count(k)} {k}' for k in sorted(set(states)))
    print(f'{len(states)} steps ({counts}) in {summary["wall_s"] / 60:.1f} min; wrote {path}')
    return 1 if 'failed' in states else 0
