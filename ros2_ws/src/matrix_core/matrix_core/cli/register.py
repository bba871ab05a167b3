"""``matrix-tracker register DATASET --out DIR``: register every frame of every drone to its reference.

Writes ``DIR/registration/Drone{N}_{TTTT}.json`` (a site dataset's drones: ``<drone>_{TTTT}.json``) with
``H_cur_to_ref`` (3x3, current raw image pixels -> reference raw image pixels), ``H_img_to_ground`` (3x3,
current raw image pixels -> the dataset's own world ground plane in metres, the frame of its calibration
files), ``confidence``, ``matches``, ``inliers``, ``inlier_error_px``, ``status``, ``reference_id``,
``backend``, ``seconds``, ``message``. Both matrices are null when status is 'failed'. ``summary.json`` adds
the error of each pair against the ground truth from the stored calibrations (mean over visible ground points,
full-resolution pixels).

No frame ends the run: a frame whose registration, check against the calibration or overlay raises (and
every frame of a drone whose reference cannot be used) is reported with the step and reason in its
summary row (``failure``), and ``stats`` counts them: ``failed`` (not registered), ``raised`` (a step
raised) and ``unmeasured`` (registered, but the error against the calibration could not be computed).

The output folder must not be, contain or lie inside the dataset; its ``registration/`` must be new or
empty (``--overwrite``: write into it).

A site dataset (``matrix-tracker simulate --site``) is read the same way: any drone names, each drone's own
camera and image size, its references those its ``site.yaml`` names, the area the site's.

The reference of each drone is the folder's ``reference/`` image and calibration; without one, the
first frame (with its stored calibration) is the reference. Obstacles and the flat-ground extent come from
the folder's ``matrix_tracker_meta.json`` when it states them (simulated folders, see
``matrix_core.register.scene``); otherwise ``--exclude_boxes`` / ``--ground_margin_m`` apply.

Overlay pictures ``DIR/registration/overlay/Drone{N}_{TTTT}.png`` (current image warped onto the reference,
checkerboarded with it, reference ground grid): the first frame of each drone always, every frame with
``--png``, every K-th frame with ``--png K``.
"""

import json
from pathlib import Path

import numpy as np
from tqdm import tqdm

from matrix_core.cli.argument_types import non_negative_int
from matrix_core.cli.selection import add_selection_arguments
from matrix_core.datasets import DatasetError, MatrixDataset, SiteDataset, open_dataset
from matrix_core.output_paths import atomic_write_text, check_output
from matrix_core.register.backends import make_backend
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.file_frame import record_name, registration_to_record
from matrix_core.register.overlay import write_registration_overlay
from matrix_core.register.registrar import Registrar
from matrix_core.register.registration import Registration, RegistrationStatus
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings
from matrix_core.settings import add_settings_arguments, settings_from_namespace


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        'register', help="register each drone's frames to its reference image", description=__doc__
    )
    add_selection_arguments(
        p,
        'register',
        'MATRIX folder (real or simulated) or site dataset',
        'output folder (gets a registration/ subfolder)',
    )
    p.add_argument(
        '--png',
        type=non_negative_int,
        nargs='?',
        const=1,
        default=0,
        metavar='K',
        help='overlay PNG of every K-th frame (bare --png: every frame); default: the first frame of each drone only',
    )
    add_settings_arguments(p, RegisterSettings)
    p.set_defaults(func=run)


def _reference(dataset: MatrixDataset, view: str):
    """(image, camera, id) of the reference of ``view``: reference/ if present, else the first frame."""
    if dataset.has_reference:
        return dataset.reference_image(view), dataset.reference_camera(view), f'{view}/reference'
    first = dataset.frames[0]
    return dataset.load_image(view, first), dataset.camera(view, first), f'{view}/frame:{first}'


def _failure(stage: str, exc: Exception) -> str:
    """One line saying which step of a frame raised and why."""
    return f'{stage}: {type(exc).__name__}: {exc}'


def _pair(view, frame, status, message, failure='', error=None, result=None) -> dict:
    """One row of summary.json (``status`` a :class:`RegistrationStatus`, written as its name); ``failure``
    names the step that raised ('' when none did)."""
    return {
        'view': view,
        'frame': frame,
        'status': status,
        'error_px': error,
        'confidence': result.confidence if result else None,
        'inliers': result.inliers if result else None,
        'seconds': result.seconds if result else None,
        'message': message,
        'failure': failure,
    }


def _register_frame(args, dataset, settings, view, frame, index, registrar, image, ref_cam, out) -> dict:
    """Register, write, measure and draw one frame; any step that raises makes the frame failed (its pair
    says which step and why) instead of ending the run."""
    name = record_name(view, frame)
    try:
        current = dataset.load_image(view, frame)
        result = registrar.register(current, frame)
    except Exception as exc:  # a bad frame (unreadable image, registration bug) must not end the batch
        reason = _failure('register', exc)
        failed = Registration.failed(reason, reference_id=registrar.reference_id, backend=registrar.backend.name)
        atomic_write_text(out / name, json.dumps(registration_to_record(failed), indent=1))
        return _pair(view, frame, RegistrationStatus.FAILED, reason, reason)
    atomic_write_text(out / name, json.dumps(registration_to_record(result), indent=1))
    failure, error = '', None
    if result.ok:
        try:
            error = homography_error_px(
                result.ref_H_img, dataset.camera(view, frame), ref_cam, dataset.area, settings.exclude_boxes
            )
        except Exception as exc:  # the registration stands; only its check against the calibration failed
            failure = _failure('error vs calibration', exc)
    if index == 0 or (args.png and index % args.png == 0):
        title = f'{view} frame {frame}: {result.status}, c {result.confidence:.2f}, {result.inliers} inliers' + (
            f', {error:.2f} px vs calibration' if error is not None else f' ({result.message or failure})'
        )
        try:
            write_registration_overlay(
                out / 'overlay' / name.replace('.json', '.png'),
                current,
                image,
                result.ref_H_img,
                ref_cam,
                dataset.area,
                title,
            )
        except Exception as exc:  # a picture is not worth the run
            failure = '; '.join(filter(None, [failure, _failure('overlay', exc)]))
    return _pair(view, frame, result.status, result.message, failure, error, result)


def run(args) -> int:
    # the output folder is checked before any work: never inside the dataset, and registration/ new or empty
    check_output(args.out, [args.dataset], overwrite=True)
    out = check_output(Path(args.out) / 'registration', overwrite=args.overwrite)
    dataset = open_dataset(args.dataset)
    if not isinstance(dataset, (MatrixDataset, SiteDataset)):
        raise DatasetError(
            f'{args.dataset}: register needs a MATRIX folder or a site dataset (drones with per-frame calibration)'
        )
    settings, note = settings_for_dataset(settings_from_namespace(RegisterSettings, args), dataset)
    if note:
        print(note)
    views, frames = dataset.select_views(args.views), dataset.select_frames(args.max_frames)
    backend = make_backend(settings)
    out.mkdir(parents=True, exist_ok=True)
    summary = []
    with tqdm(total=len(views) * len(frames), desc='register', unit='image') as bar:
        for view in views:
            try:
                image, ref_cam, ref_id = _reference(dataset, view)
                registrar = Registrar(settings, image, ref_cam, dataset.area, ref_id, backend)
            except Exception as exc:  # one drone without a usable reference: its frames fail, the others run
                reason = _failure('reference', exc)
                tqdm.write(f'{view}: {reason}')
                summary += [_pair(view, frame, RegistrationStatus.FAILED, reason, reason) for frame in frames]
                bar.update(len(frames))
                continue
            for index, frame in enumerate(frames):
                pair = _register_frame(args, dataset, settings, view, frame, index, registrar, image, ref_cam, out)
                if pair['failure']:
                    tqdm.write(f'{view} frame {frame}: {pair["failure"]}')
                summary.append(pair)
                bar.update()
    errors = np.array([s['error_px'] for s in summary if s['error_px'] is not None])
    seconds = [s['seconds'] for s in summary if s['seconds'] is not None]
    failed = sum(s['status'] is not RegistrationStatus.OK for s in summary)
    stats = {
        'pairs': len(summary),
        'failed': failed,
        'raised': sum(bool(s['failure']) for s in summary),
        'unmeasured': sum(s['status'] is RegistrationStatus.OK and s['error_px'] is None for s in summary),
        'backend': backend.name,
        'error_px_median': float(np.median(errors)) if len(errors) else None,
        'error_px_max': float(np.max(errors)) if len(errors) else None,
        'seconds_median': float(np.median(seconds)) if seconds else None,
    }
    pairs = [{**s, 'status': str(s['status'])} for s in summary]
    atomic_write_text(out / 'summary.json', json.dumps({'stats': stats, 'pairs': pairs}, indent=1))
    print(
        f'registered {len(summary) - failed}/{len(summary)} images with {backend.name}; error vs stored '
        f'calibration: median {stats["error_px_median"]} px, max {stats["error_px_max"]} px '
        f'({stats["unmeasured"]} registered but not measured); {stats["raised"]} frame(s) raised (reason in '
        f'summary.json "failure"); median {stats["seconds_median"]} s per image; wrote {out}'
    )
    return 0
