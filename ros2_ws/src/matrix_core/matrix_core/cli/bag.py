"""``matrix-tracker bag``: turn a MATRIX-format folder or a site dataset into a rosbag2 (MCAP) sequence bag, or list
a bag.

    matrix-tracker bag ../shared/matrix_sample --out bags/matrix_sample      # write
    matrix-tracker bag bags/matrix_sample                                     # list topics and counts

Writing refuses an ``--out`` that is, contains or lies inside the source folder, and an existing ``--out``.
An image that cannot be read or is cut short ends the run with its name, and no bag is left at ``--out``
(the bag is written under a temporary name and moved there when complete): a bag is the whole sequence or
nothing, as its frame ``i`` is the folder's ``i``-th frame.

A damaged bag (cut short, overwritten, left by a killed writer) is listed with the messages before the
damage, then the reason, and exit code 1.

``--site SITE``: the source's area and drones must be the site's (an error naming what differs, before any
work); default: the site a site dataset names, else MATRIX.

Topics and conventions: see ``matrix_core.bags`` and bags/README.md.
"""

import sys
from pathlib import Path

from matrix_core.bags import write_sequence_bag
from matrix_core.bags.salvage import topic_counts
from matrix_core.cli.argument_types import add_site_argument
from matrix_core.datasets import DatasetError, open_dataset
from matrix_core.output_paths import atomic_folder, check_output


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'bag', help='write a MATRIX-format folder as a rosbag2 sequence bag, or list a bag', description=__doc__
    )
    p.add_argument('source', help='MATRIX-format folder or site dataset (to write a bag) or a bag folder (to list it)')
    p.add_argument('--out', help='bag folder to create (must not exist)')
    p.add_argument('--compressed', action='store_true', help='store JPEG CompressedImage instead of raw Image')
    add_site_argument(p, 'the source folder')
    p.set_defaults(func=run)


def run(args) -> int:
    source = Path(args.source)
    if (source / 'metadata.yaml').is_file() or (source.is_dir() and any(source.glob('*.mcap'))):
        return _list(source)
    if not args.out:
        raise ValueError('--out BAG is required to write a bag (or give a bag folder to list it)')
    out = Path(args.out)
    check_output(out, [source])
    if out.exists():
        raise FileExistsError(f'{out} exists; rosbag2 writes a new folder')
    dataset = open_dataset(source)
    if not hasattr(dataset, 'pedestrian_positions'):  # the bag carries every person's ground-truth position
        raise DatasetError(f'{source} is a {dataset.format_name} folder; bag needs a MATRIX folder or a site dataset')
    from matrix_core.site.parameter import dataset_site

    dataset_site(args.site, dataset, f'--site {args.site}: {source}')  # before any work: the data is of the site
    # written under a temporary name and moved to --out when every frame is in it: a bad image (named in the
    # error) or an interrupted run leaves no bag that a player or `bag` listing could take for the sequence
    with atomic_folder(out) as partial:
        write_sequence_bag(dataset, partial, compressed=args.compressed)
    print(f'wrote {out}')
    return 0


def _list(bag: Path) -> int:
    """Topics, types and message counts of a bag; of a damaged one, those before the damage, then why (1)."""
    topics, damage = topic_counts(bag)
    for topic, (msgtype, count) in sorted(topics.items()):
        print(f'{topic:40s} {msgtype:36s} {count:6d}')
    if damage:
        print(f'damaged bag: {damage}', file=sys.stderr)
    return 1 if damage else 0
