"""``matrix-tracker simulate``: generate a seeded MATRIX-like sequence (folder + optional rosbag2); with ``--site``
a site file's scene, written as a site dataset (docs/site-file.md)."""

from matrix_core.output_paths import check_output
from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.sim.settings import SimulateSettings


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'simulate', help='generate a seeded MATRIX-like scene sequence (and a bag)', description=__doc__
    )
    add_settings_arguments(p, SimulateSettings)
    p.set_defaults(func=run)


def run(args) -> int:
    import json

    from matrix_core.sim.sequence import SUMMARY_FILE, simulate

    settings = settings_from_namespace(SimulateSettings, args)
    check_output(settings.out, [settings.replay])  # before any work: never into the replayed folder
    out = simulate(settings)
    summary = json.loads((out / SUMMARY_FILE).read_text())
    if settings.site_dataset:
        what = f'site {settings.site} (site dataset, image scale {settings.image_scale:g}, seed {settings.seed})'
    else:
        what = f'{settings.config} (seed {settings.seed}, {settings.width}x{settings.height})'
    written, failed = summary['frames_written'], summary['frames_failed']
    print(f'wrote {written} of {settings.frames} frames of {what} to {out}; {failed} failed')
    for f in summary['failed_frames']:
        print(f'  frame {f["frame"]}: {f["reason"]}')
    return 0
