"""``matrix-tracker site check SITE``: load and validate a site file (docs/site-file.md) and summarise it.

A bad file is one line naming the file, the key and the fault, exit status 2. Missing reference files are
listed (exit 0) unless ``--require-references``, which makes them an error as for a command that reads them.
"""

from matrix_core.site.load import load_site
from matrix_core.site.shipped import shipped_sites, site_path
from matrix_core.site.summary import format_site


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'site', help='site files: check one (area, drones, boards, references)', description=__doc__
    )
    actions = p.add_subparsers(dest='site_command', metavar='ACTION', required=True)
    check = actions.add_parser('check', help='validate a site file and print its summary', description=__doc__)
    check.add_argument('site', help=f'site file, or the name of a shipped one ({", ".join(shipped_sites())})')
    check.add_argument(
        '--require-references',
        action='store_true',
        help='fail (exit 2) unless every drone\'s reference image and calibration can be read',
    )
    check.set_defaults(func=run_check)


def run_check(args) -> int:
    site = load_site(site_path(args.site), require_references=args.require_references)
    text, _ = format_site(site)
    print(text)
    return 0
