"""``matrix-tracker bag``: turn a MATRIX-format folder into a rosbag2 (MCAP) sequence bag, or list a bag.

    matrix-tracker bag ../shared/matrix_sample --out bags/matrix_sample      # write
    matrix-tracker bag bags/matrix_sample                                     # list topics and counts

Topics and conventions: see ``matrix_core.bags`` (README, section "Bags").
"""

from pathlib import Path

from matrix_core.bags import bag_topics, write_sequence_bag
from matrix_core.datasets import MatrixDataset


def add_parser(subparsers) -> None:
    p = subparsers.add_parser('bag', help='write a MATRIX-format folder as a rosbag2 sequence bag, or list a bag',
                              description=__doc__)
    p.add_argument('source', help='MATRIX-format folder (to write a bag) or a bag folder (to list it)')
    p.add_argument('--out', help='bag folder to create (must not exist)')
    p.add_argument('--compressed', action='store_true', help='store JPEG CompressedImage instead of raw Image')
    p.set_defaults(func=run)


def run(args) -> int:
    source = Path(args.source)
    if (source / 'metadata.yaml').is_file():
        for topic, (msgtype, count) in sorted(bag_topics(source).items()):
            print(f'{topic:40s} {msgtype:36s} {count:6d}')
        return 0
    if not args.out:
        raise ValueError('--out BAG is required to write a bag (or give a bag folder to list it)')
    out = Path(args.out)
    if out.exists():
        raise FileExistsError(f'{out} exists; rosbag2 writes a new folder')
    path = write_sequence_bag(MatrixDataset(source), out, compressed=args.compressed)
    print(f'wrote {path}')
    return 0
