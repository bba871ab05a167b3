"""``matrix-tracker experiments --mode quick|medium|full``: the paper's five experiments on simulated MATRIX
variants (simple vs complex, static baselines and ablations, transfer, camera dropout, run-to-run
variation), then ``--report`` (RESULTS.md) and its PNGs, written from the run's metrics.json files.

Everything goes to ``OUT/<mode>/`` (datasets, calibrations, checkpoints, metrics); finished steps are
cached there, so a rerun resumes where the last one stopped. ``quick`` (about 4 minutes on one thread) is
a smoke test; ``full`` gives meaningful numbers (many hours on one thread). ``--report-only`` rewrites
the report from an existing run.
"""


def add_parser(subparsers) -> None:
    from matrix_core.experiments.sizes import SIZES

    p = subparsers.add_parser('experiments', help="run the paper's experiments and write docs/RESULTS.md",
                              description=__doc__)
    p.add_argument('--mode', choices=list(SIZES), default='quick', help='run size (default: quick)')
    p.add_argument('--out', default='out/experiments', help='run folder root (the run goes to OUT/MODE)')
    p.add_argument('--report', default='docs/RESULTS.md', help='markdown report to write')
    p.add_argument('--images', help='folder for the PNGs (default: images/results next to the report)')
    p.add_argument('--threads', type=int, default=1, help='torch threads (default 1)')
    p.add_argument('--report-only', action='store_true', help='only rewrite the report from OUT/MODE')
    p.add_argument('--no-progress', action='store_true', help='no progress bars')
    p.set_defaults(func=run)


def run(args) -> int:
    from pathlib import Path

    from matrix_core.experiments.report import write_report
    from matrix_core.experiments.runner import run_experiments
    from matrix_core.experiments.sizes import SIZES

    size = SIZES[args.mode]
    if args.report_only:
        path = write_report(Path(args.out) / size.name, args.report, args.images)
        print(f'wrote {path}')
        return 0
    summary, path = run_experiments(size, args.out, args.report, args.images, args.threads, not args.no_progress)
    states = [s['state'] for s in summary['steps'].values()]
    counts = ', '.join(f'{states.count(k)} {k}' for k in sorted(set(states)))
    print(f'{len(states)} steps ({counts}) in {summary["wall_s"] / 60:.1f} min; wrote {path}')
    return 1 if 'failed' in states else 0
