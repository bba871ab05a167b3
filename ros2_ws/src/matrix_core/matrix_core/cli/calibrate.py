"""``matrix-tracker calibrate DATASET --out DIR``: per-frame checkerboard calibration of every drone.

Calibrates every frame of every view of a MATRIX-format folder from its images alone (intrinsics and
boards from ``--config``; the first frame's prior from ``DATASET/reference/calibrations`` when present,
else from the config's ``initial_poses``). Writes ``DIR/calibrations/{intrinsic,extrinsic}/`` in the
dataset's own file format and world frame (with links to the images in ``DIR/image_subsets``, so that
``open_dataset(DIR)`` reads it like any MATRIX folder) and ``DIR/calibration_status.csv``.
Frames that end stale are written with the last good pose (the table says so); failed ones are not written.
:func:`simulated_sequence` makes a sequence to calibrate (the calibration's tests and benchmarks).
"""

import csv
import os
from pathlib import Path

from tqdm import tqdm

from matrix_core.cli.selection import add_selection_arguments
from matrix_core.calib.drone_calibrator import OK, DroneCalibrator
from matrix_core.calib.evaluation import pose_errors, summarize_errors
from matrix_core.calib.scene import load_scene
from matrix_core.calib.prior import initial_prior
from matrix_core.calib.settings import CalibSettings
from matrix_core.cli.main import main as cli_main
from matrix_core.datasets import DatasetError, MatrixDataset, MatrixWriter, open_dataset
from matrix_core.settings import add_settings_arguments, settings_from_namespace

STATUS_FILE = 'calibration_status.csv'
COLUMNS = ('view', 'frame', 'status', 'rms_px', 'corners', 'pieces_found', 'pieces_assigned', 'tracked', 'age_s',
           'time_s', 'rot_err_deg', 'centre_err_m', 'message')


def add_parser(subparsers) -> None:
    p = subparsers.add_parser('calibrate', help='estimate every frame\'s camera pose from the ground checkerboards',
                              description=__doc__)
    add_selection_arguments(p, 'calibrate', 'MATRIX-format folder', 'output folder')
    p.add_argument('--frame-period', type=float, default=0.5, help='seconds between frames (for ages)')
    p.add_argument('--compare', action='store_true', help='print errors against the stored calibrations')
    add_settings_arguments(p, CalibSettings)
    p.set_defaults(func=run)


def calibrate_dataset(dataset: MatrixDataset, out: Path, settings: CalibSettings, views=(), max_frames=0,
                      frame_period=0.5, compare=False) -> list:
    """Run the calibration over ``dataset``; returns the status rows (also written to the CSV)."""
    scene = load_scene(settings.config)
    views, frames = dataset.select_views(views), dataset.select_frames(max_frames)
    writer = MatrixWriter(out, area=dataset.area, extra_meta={'calibrated_from': str(dataset.root)})
    rows = []
    with tqdm(total=len(views) * len(frames), desc='calibrate', unit='image') as bar:
        for view in views:
            prior, prior_image = initial_prior(scene, view, dataset)
            calibrator = DroneCalibrator(scene, settings, prior, prior_image)
            for index, frame in enumerate(frames):
                result = calibrator.process(dataset.load_image(view, frame), index * frame_period)
                row = {'view': view, 'frame': frame, 'status': result.status, 'rms_px': result.rms_px,
                       'corners': result.corners, 'pieces_found': result.pieces_found,
                       'pieces_assigned': result.pieces_assigned, 'tracked': result.tracked, 'age_s': result.age_s,
                       'time_s': result.timings_s.get('total', float('nan')), 'rot_err_deg': float('nan'),
                       'centre_err_m': float('nan'), 'message': result.message}
                if result.camera is not None:
                    writer.write_camera(view, frame, result.camera)
                    _link_image(dataset, out, view, frame)
                    if compare:
                        row['rot_err_deg'], row['centre_err_m'] = pose_errors(result.camera,
                                                                              dataset.camera(view, frame))
                rows.append(row)
                bar.update(1)
    with open(out / STATUS_FILE, 'w', newline='') as fh:
        w = csv.DictWriter(fh, COLUMNS)
        w.writeheader()
        w.writerows(rows)
    return rows


def _link_image(dataset, out: Path, view: str, frame: int) -> None:
    src = dataset.image_path(view, frame).resolve()
    dst = out / 'image_subsets' / view / src.name
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.exists():
        os.symlink(src, dst)


def simulated_sequence(variant: str, frames: int, seed: int, out) -> Path:
    """Write ``frames`` frames of simulator ``variant`` to ``out`` (MATRIX format) and return ``out``: the
    sequence ``matrix-tracker simulate`` writes, so that tests and benchmarks calibrate what a user would."""
    out = Path(out)
    code = cli_main(['simulate', '--config', variant, '--frames', str(frames), '--seed', str(seed),
                     '--out', str(out)])
    if code != 0:
        raise RuntimeError(f'matrix-tracker simulate {variant} failed with exit code {code}')
    return out


def run(args) -> int:
    settings = settings_from_namespace(CalibSettings, args)
    dataset = open_dataset(args.dataset)
    if not isinstance(dataset, MatrixDataset):
        raise DatasetError(f'{args.dataset} is a {dataset.format_name} folder; calibrate needs MATRIX format')
    out = Path(args.out)
    rows = calibrate_dataset(dataset, out, settings, args.views, args.max_frames, args.frame_period,
                             args.compare)
    s = summarize_errors(rows) if args.compare else None
    counts = {k: sum(r['status'] == k for r in rows) for k in (OK, 'stale', 'failed')}
    print(f'{len(rows)} images: {counts}; wrote {out / "calibrations"} and {out / STATUS_FILE}')
    if s and s['ok']:
        print(f"vs stored calibration (ok frames): rotation median {s['rot_median_deg']:.3f} deg, "
              f"max {s['rot_max_deg']:.3f} deg; centre median {s['centre_median_m']:.3f} m, "
              f"max {s['centre_max_m']:.3f} m")
        for r in rows:
            print(f"  {r['view']} {r['frame']:04d} {r['status']:6s} rot {r['rot_err_deg']:.3f} deg "
                  f"centre {r['centre_err_m']:.3f} m  {r['corners']} corners  {r['message']}")
    return 0
