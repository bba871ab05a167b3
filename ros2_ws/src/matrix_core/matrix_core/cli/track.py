"""``matrix-tracker track DETS.txt --out TRACKS.txt``: run the BEV tracker on detections from any detector.

DETS lines: ``frame x y score`` (world metres, integer frames; ``score`` optional, default 1). Frames
missing between the first and the last are processed as frames without detections. Writes
``frame id x y`` lines (the tracker's filtered positions of confirmed tracks matched in that frame).
"""

import numpy as np

from matrix_core.metrics import BevPoints, read_bev_points, write_bev_points
from matrix_core.output_paths import add_overwrite_argument, check_output
from matrix_core.settings import add_settings_arguments, settings_from_namespace
from matrix_core.tracking import BevDetections, BevTracker, TrackerSettings


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'track', help='track BEV detections ("frame x y score") into "frame id x y"', description=__doc__
    )
    p.add_argument('detections', help='text file, lines "frame x y [score]"')
    p.add_argument('--out', required=True, help='output text file, lines "frame id x y" (new or empty)')
    add_overwrite_argument(p)
    add_settings_arguments(p, TrackerSettings)
    p.set_defaults(func=run)


def track_points(dets: BevPoints, settings: TrackerSettings) -> BevPoints:
    """Run a fresh tracker over every frame from the first to the last detection frame."""
    tracker = BevTracker(settings)
    rows = dets.by_frame()
    frames, ids, xy = [], [], []
    if rows:
        for f in range(min(rows), max(rows) + 1):
            r = rows.get(f, np.zeros(0, dtype=int))
            for t in tracker.update(BevDetections(dets.xy[r], dets.scores[r])):
                frames.append(f)
                ids.append(t.track_id)
                xy.append(t.xy)
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def run(args) -> int:
    check_output(args.out, [args.detections], args.overwrite)
    dets = read_bev_points(args.detections, with_ids=False)
    tracks = track_points(dets, settings_from_namespace(TrackerSettings, args))
    write_bev_points(args.out, tracks)
    print(
        f'{len(dets)} detections in {len(dets.frame_numbers)} frames -> {len(tracks)} track points, '
        f'{len(np.unique(tracks.ids))} tracks: {args.out}'
    )
    return 0
