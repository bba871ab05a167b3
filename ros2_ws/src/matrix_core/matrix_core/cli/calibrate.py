"""``matrix-tracker calibrate DATASET --out DIR``: per-frame checkerboard calibration of every drone.

Calibrates every frame of every view of a MATRIX-format folder (intrinsics and boards from ``--config``;
the first frame's prior from ``DATASET/reference/calibrations`` when present, else from the config's
``initial_poses``). Writes ``DIR/calibrations/{intrinsic,extrinsic}/`` in the dataset's own file format and
world frame (with links to the images in ``DIR/image_subsets``, so that ``open_dataset(DIR)`` reads it like
any MATRIX folder) and ``DIR/calibration_status.csv``.

A site dataset (``matrix-tracker simulate --site``) is calibrated with its site's boards and each drone's own
camera and image size (``--config`` given: that scene instead), the prior from its references; ``DIR`` is then
a site dataset of its own (``datasets.site_writer.SiteCalibrationWriter``: ``DIR/calibrations/<drone>/``,
links in ``DIR/images/<drone>/``, its ``site.yaml`` naming the source's references).

``--registration REG``: the ``--out`` folder of ``matrix-tracker register`` (``REG/registration/Drone{N}_{TTTT}.json``).
Each frame is then calibrated as the live ``calib`` node with ``use_registration`` does: the camera its
registration implies predicts the boards; a frame without a record, or whose registration failed or is not
a rigid camera, is calibrated from the image motion (column ``guide`` says which).

Only ``ok`` poses are written by default: a ``stale`` frame (no acceptable pose in its image; the calibrator
holds its last good pose) is listed in the CSV but gets no calibration file, so that no MATRIX reader takes
it for a measurement; ``--write-stale`` writes those last good poses too (column ``written``). Failed
frames are never written.

The output folder must not be, contain or lie inside the dataset or ``--registration`` folder, and must be
new or empty (``--overwrite``: write into it); the views, the records and the scene are checked before the
first frame.

No frame ends the run: a frame whose image cannot be read or whose calibration raises (and every frame of a
drone without a prior) is ``failed`` with the step in ``failure`` and the reason in ``message``; the summary
counts them. :func:`simulated_sequence` makes a sequence to calibrate (the calibration's tests and
benchmarks).
"""

import csv
import io
import os
from pathlib import Path

from tqdm import tqdm

from matrix_core.cli.argument_types import positive_float
from matrix_core.cli.selection import add_selection_arguments
from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.evaluation import pose_errors, summarize_errors
from matrix_core.calib.status import CalibStatus
from matrix_core.calib.scene import load_scene
from matrix_core.calib.prior import initial_prior
from matrix_core.calib.settings import CalibSettings
from matrix_core.cli.main import main as cli_main
from matrix_core.datasets import DatasetError, MatrixDataset, MatrixWriter, SiteDataset, open_dataset
from matrix_core.datasets.site_writer import SiteCalibrationWriter
from matrix_core.register.file_frame import read_registration
from matrix_core.output_paths import atomic_write_text, check_output
from matrix_core.settings import add_settings_arguments, settings_from_namespace

STATUS_FILE = 'calibration_status.csv'
COLUMNS = (
    'view',
    'frame',
    'status',
    'written',
    'rms_px',
    'corners',
    'pieces_found',
    'pieces_assigned',
    'tracked',
    'age_s',
    'time_s',
    'rot_err_deg',
    'centre_err_m',
    'registration',
    'guide',
    'failure',
    'message',
)
NAN = float('nan')
RECORD_PATTERN = '*_[0-9][0-9][0-9][0-9].json'  # register's records: Drone3_0017.json, kestrel_0017.json


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'calibrate', help='estimate every frame\'s camera pose from the ground checkerboards', description=__doc__
    )
    add_selection_arguments(p, 'calibrate', 'MATRIX-format folder or site dataset', 'output folder')
    p.add_argument('--frame-period', type=positive_float, default=0.5, help='seconds between frames (for ages)')
    p.add_argument('--compare', action='store_true', help='print errors against the stored calibrations')
    p.add_argument(
        '--registration',
        metavar='REG',
        default=None,
        help='the --out folder of `matrix-tracker register` on this dataset: each frame\'s registration '
        'guides its calibration (as the live calib node with use_registration)',
    )
    p.add_argument(
        '--write-stale',
        action='store_true',
        help='also write the last good pose of stale frames as calibration files (default: only ok '
        'frames; the CSV lists every frame)',
    )
    add_settings_arguments(p, CalibSettings)
    p.set_defaults(func=run)


def registration_folder(path) -> Path:
    """``path/registration`` (the ``--out`` of ``matrix-tracker register``), or ``path`` itself when it holds
    the records; :class:`DatasetError` when neither has any."""
    path = Path(path)
    for folder in (path / 'registration', path):
        if folder.is_dir() and any(folder.glob(RECORD_PATTERN)):
            return folder
    raise DatasetError(
        f'{path}: no registration records ({RECORD_PATTERN}) in it or in its registration/ '
        f'(the --out folder of `matrix-tracker register`)'
    )


def _row(view, frame, status, message, failure='', result=None, registration='') -> dict:
    """One row of the CSV; ``failure`` names the step that raised ('' when none did)."""
    r = result
    return {
        'view': view,
        'frame': frame,
        'status': status,
        'written': False,
        'rms_px': r.rms_px if r else NAN,
        'corners': r.corners if r else 0,
        'pieces_found': r.pieces_found if r else 0,
        'pieces_assigned': r.pieces_assigned if r else 0,
        'tracked': r.tracked if r else False,
        'age_s': r.age_s if r else 0.0,
        'time_s': r.timings_s.get('total', NAN) if r else NAN,
        'rot_err_deg': NAN,
        'centre_err_m': NAN,
        'registration': registration,
        'guide': r.motion if r else '',
        'failure': failure,
        'message': message,
    }


def _failure(step: str, exc: Exception) -> str:
    return f'{step}: {type(exc).__name__}: {exc}'


def _registration_of(registrations, view, frame) -> tuple:
    """(Registration or None, what the CSV says of it): '' without ``--registration``, 'missing', or its
    status (with the reason when not ok)."""
    if registrations is None:
        return None, ''
    registration = read_registration(registrations, view, frame)
    if registration is None:
        return None, 'missing'
    return registration, f'{registration.status}' + (f': {registration.message}' if not registration.ok else '')


def _calibrate_frame(dataset, out, writer, calibrator, view, frame, stamp, registrations, write_stale, compare) -> dict:
    """Calibrate, write and measure one frame; a step that raises makes the frame failed (its row says which
    and why) instead of ending the run."""
    step = 'read image'
    try:
        image = dataset.load_image(view, frame)
        step = 'registration'
        registration, said = _registration_of(registrations, view, frame)
        step = 'calibrate'
        result = calibrator.process(image, stamp, registration)
    except Exception as exc:  # one bad frame (unreadable image, wrong size, calibrator bug) must not end the batch
        reason = _failure(step, exc)
        return _row(view, frame, CalibStatus.FAILED, reason, step, registration=said if step == 'calibrate' else '')
    row = _row(view, frame, result.status, result.message, result=result, registration=said)
    if result.camera is None:
        return row
    if compare:
        try:
            row['rot_err_deg'], row['centre_err_m'] = pose_errors(result.camera, dataset.camera(view, frame))
        except Exception as exc:  # the pose stands; only its check against the stored calibration failed
            row['failure'], row['message'] = 'compare', f'{row["message"]}; {_failure("compare", exc)}'
    if result.status is CalibStatus.OK or write_stale:
        try:
            writer.write_camera(view, frame, result.camera)
            _link_image(writer, dataset, out, view, frame)
            row['written'] = True
        except Exception as exc:
            row['failure'], row['message'] = 'write', f'{row["message"]}; {_failure("write", exc)}'
    return row


def _scenes(dataset, settings: CalibSettings, views) -> dict:
    """view -> its calibration scene: ``--config``'s for every view; a site dataset's, without ``--config``:
    the site's boards with that drone's camera (``site.calib_scene``)."""
    if settings.config or not isinstance(dataset, SiteDataset):
        scene = load_scene(settings.config)
        return dict.fromkeys(views, scene)
    from matrix_core.site.calib_scene import site_calib_scene

    return {v: site_calib_scene(dataset.site, dataset.site.drone(v)) for v in views}


def _writer(dataset, out: Path):
    extra = {'calibrated_from': str(dataset.root)}
    if isinstance(dataset, SiteDataset):
        return SiteCalibrationWriter(out, dataset, extra)
    return MatrixWriter(out, area=dataset.area, extra_meta=extra)


def calibrate_dataset(
    dataset,
    out: Path,
    settings: CalibSettings,
    views=(),
    max_frames=0,
    frame_period=0.5,
    compare=False,
    registration_dir=None,
    write_stale=False,
) -> list:
    """Run the calibration over ``dataset``; returns the status rows (also written to the CSV).
    ``registration_dir``: the ``--out`` folder of ``matrix-tracker register`` (see :func:`registration_folder`)
    whose records guide the frames; ``write_stale``: write stale frames' last good poses too."""
    views, frames = dataset.select_views(views), dataset.select_frames(max_frames)
    scenes = _scenes(dataset, settings, views)
    registrations = None if registration_dir is None else registration_folder(registration_dir)
    writer = _writer(dataset, out)
    rows = []
    with tqdm(total=len(views) * len(frames), desc='calibrate', unit='image') as bar:
        for view in views:
            try:
                scene = scenes[view]
                calibrator = DroneCalibrator(scene, settings, *initial_prior(scene, view, dataset))
            except Exception as exc:  # one drone without a usable prior: its frames fail, the others run
                reason = _failure('prior', exc)
                tqdm.write(f'{view}: {reason}')
                rows += [_row(view, frame, CalibStatus.FAILED, reason, 'prior') for frame in frames]
                bar.update(len(frames))
                continue
            for index, frame in enumerate(frames):
                row = _calibrate_frame(
                    dataset,
                    out,
                    writer,
                    calibrator,
                    view,
                    frame,
                    index * frame_period,
                    registrations,
                    write_stale,
                    compare,
                )
                if row['failure']:
                    tqdm.write(f'{view} frame {frame}: {row["message"]}')
                rows.append(row)
                bar.update(1)
    table = io.StringIO(newline='')
    w = csv.DictWriter(table, COLUMNS)
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(out / STATUS_FILE, table.getvalue())
    return rows


def _link_image(writer, dataset, out: Path, view: str, frame: int) -> None:
    if isinstance(writer, SiteCalibrationWriter):
        src, dst = writer.image_link(view, frame)
    else:
        src = dataset.image_path(view, frame).resolve()
        dst = out / 'image_subsets' / view / src.name
    dst.parent.mkdir(parents=True, exist_ok=True)
    if not dst.exists():
        os.symlink(src, dst)


def simulated_sequence(variant: str, frames: int, seed: int, out) -> Path:
    """Write ``frames`` frames of simulator ``variant`` to ``out`` (MATRIX format) and return ``out``: the
    sequence ``matrix-tracker simulate`` writes, so that tests and benchmarks calibrate what a user would."""
    out = Path(out)
    code = cli_main(['simulate', '--config', variant, '--frames', str(frames), '--seed', str(seed), '--out', str(out)])
    if code != 0:
        raise RuntimeError(f'matrix-tracker simulate {variant} failed with exit code {code}')
    return out


def run(args) -> int:
    settings = settings_from_namespace(CalibSettings, args)
    out = check_output(args.out, [args.dataset, args.registration, settings.config], args.overwrite)
    dataset = open_dataset(args.dataset)
    if not isinstance(dataset, (MatrixDataset, SiteDataset)):
        raise DatasetError(
            f'{args.dataset} is a {dataset.format_name} folder; calibrate needs MATRIX format or a site dataset'
        )
    views = dataset.select_views(args.views)  # checked before the first frame, as the records and the scenes
    if args.registration is not None:
        registration_folder(args.registration)
    _scenes(dataset, settings, views)
    rows = calibrate_dataset(
        dataset,
        out,
        settings,
        args.views,
        args.max_frames,
        args.frame_period,
        args.compare,
        args.registration,
        args.write_stale,
    )
    counts = {
        str(k): sum(r['status'] is k for r in rows) for k in (CalibStatus.OK, CalibStatus.STALE, CalibStatus.FAILED)
    }
    raised = sum(bool(r['failure']) for r in rows)
    written = sum(r['written'] for r in rows)
    stale_kept = sum(r['status'] is CalibStatus.STALE and not r['written'] for r in rows)
    guided = sum(r['guide'] == 'registration' for r in rows)
    print(
        f'{len(rows)} images: {counts}; {raised} raised (step in the CSV\'s "failure"); wrote {written} '
        f'calibration(s) to {out / "calibrations"}'
        + (f' ({stale_kept} stale not written: --write-stale writes them)' if stale_kept else '')
        + (f'; {guided} guided by their registration' if args.registration else '')
        + f'; table {out / STATUS_FILE}'
    )
    s = summarize_errors(rows) if args.compare else None
    if s and s['ok']:
        print(
            f"vs stored calibration (ok frames): rotation median {s['rot_median_deg']:.3f} deg, "
            f"max {s['rot_max_deg']:.3f} deg; centre median {s['centre_median_m']:.3f} m, "
            f"max {s['centre_max_m']:.3f} m"
        )
        for r in rows:
            print(
                f"  {r['view']} {r['frame']:04d} {r['status']:6s} rot {r['rot_err_deg']:.3f} deg "
                f"centre {r['centre_err_m']:.3f} m  {r['corners']} corners  {r['message']}"
            )
    return 0
