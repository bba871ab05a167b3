"""Arguments of the batch commands that run over a dataset's drones and frames (register, calibrate)."""

from matrix_core.cli.argument_types import non_negative_int
from matrix_core.output_paths import add_overwrite_argument


def add_selection_arguments(parser, verb: str, dataset_help: str, out_help: str) -> None:
    """``dataset``, ``--out``, ``--overwrite``, ``--views`` and ``--max-frames`` (read back with
    ``MultiviewDataset.select_views`` and ``select_frames``)."""
    parser.add_argument('dataset', help=dataset_help)
    parser.add_argument('--out', required=True, help=out_help + ' (not inside the dataset; new or empty)')
    add_overwrite_argument(parser)
    parser.add_argument('--views', nargs='*', default=[], help=f'drones to {verb}, e.g. D1 D3 (default: all)')
    parser.add_argument(
        '--max-frames', type=non_negative_int, default=0, help=f'{verb} at most this many frames (0 = all)'
    )
