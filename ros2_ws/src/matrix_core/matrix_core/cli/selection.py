"""Arguments of the batch commands that run over a dataset's drones and frames (register, calibrate)."""


def add_selection_arguments(parser, verb: str, dataset_help: str, out_help: str) -> None:
    """``dataset``, ``--out``, ``--views`` and ``--max-frames`` (read back with ``MultiviewDataset.select_views``
    and ``select_frames``)."""
    parser.add_argument('dataset', help=dataset_help)
    parser.add_argument('--out', required=True, help=out_help)
    parser.add_argument('--views', nargs='*', default=[], help=f'drones to {verb}, e.g. D1 D3 (default: all)')
    parser.add_argument('--max-frames', type=int, default=0, help=f'{verb} at most this many frames (0 = all)')
