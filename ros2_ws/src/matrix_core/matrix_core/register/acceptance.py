"""Acceptance figures of a whole MATRIX folder: register every (drone, frame) pair to the drone's reference
and measure each against the ground truth from the stored calibrations (tests, scripts/bench_register.py).

Images smaller than the paper's 1920x1080 get the settings that see the same 480x270 feature image and the
same full-resolution inlier threshold, and their errors are reported in FULL-RESOLUTION-EQUIVALENT pixels
(pixels of the folder's images x REFERENCE_WIDTH / width), so the criteria (median <= 0.5 px, worst <= 3 px) read
the same at every size.
"""

import time
from dataclasses import replace

import numpy as np
from tqdm import tqdm

from matrix_core.register.backends import make_backend
from matrix_core.register.evaluate import homography_error_px
from matrix_core.register.registrar import Registrar
from matrix_core.register.scene import settings_for_dataset
from matrix_core.register.settings import RegisterSettings
from matrix_core.reference_size import REFERENCE_WIDTH


def settings_for_width(settings: RegisterSettings, width: int) -> RegisterSettings:
    """``settings`` (chosen for 1920-px images) for images ``width`` px wide: same feature-image size and
    the same inlier threshold in full-resolution-equivalent pixels."""
    factor = REFERENCE_WIDTH / width
    return replace(
        settings,
        scale=min(1.0, settings.scale * factor),
        track_refine_scale=min(1.0, settings.track_refine_scale * factor),
        homography_ransac_px=settings.homography_ransac_px / factor,
    )


def acceptance_run(dataset, settings: RegisterSettings = None, views=None, frames=None, progress: bool = False) -> dict:
    """Register ``frames`` (default all) of ``views`` (default all) of a MATRIX folder with a ``reference/``.

    Returns a dict: ``pairs``, ``failed`` ({'D1/7': reason}), ``errors_px`` (list, full-resolution-equivalent
    pixels, registered pairs only), ``error_px_median``, ``error_px_max``, ``seconds_median`` (per pair),
    ``cpu_seconds`` (list: CPU time of each pair's registration), ``tracked`` (pairs registered by flow, mode track),
    ``anchors_by_flow`` (anchors made by flow to the reference, mode track),
    ``width`` (of the folder's images), ``settings`` (as used, after :func:`settings_for_width` and the
    dataset's own scene, see :mod:`matrix_core.register.scene`).
    """
    views = list(views or dataset.views)
    frames = list(dataset.frames if frames is None else frames)
    width = dataset.reference_camera(views[0]).width
    settings = settings_for_width(settings or RegisterSettings(), width)
    settings, _ = settings_for_dataset(settings, dataset)
    backend = make_backend(settings)
    factor = REFERENCE_WIDTH / width
    failed, errors, seconds, cpu, tracked, anchors_by_flow = {}, [], [], [], 0, 0
    with tqdm(total=len(views) * len(frames), desc='register', unit='pair', disable=not progress) as bar:
        for view in views:
            ref = dataset.reference_camera(view)
            image = dataset.reference_image(view)
            registrar = Registrar(settings, image, ref, dataset.area, f'{view}/reference', backend)
            for frame in frames:
                image = dataset.load_image(view, frame)
                start = time.process_time()
                r = registrar.register(image, frame)
                cpu.append(time.process_time() - start)
                seconds.append(r.seconds)
                tracked += r.message.startswith('tracked')
                anchors_by_flow += r.message.startswith('anchor by flow')
                if r.ok:
                    errors.append(
                        factor
                        * homography_error_px(
                            r.ref_H_img, dataset.camera(view, frame), ref, dataset.area, settings.exclude_boxes
                        )
                    )
                else:
                    failed[f'{view}/{frame}'] = r.message
                bar.update()
    return {
        'pairs': len(seconds),
        'failed': failed,
        'errors_px': errors,
        'error_px_median': float(np.median(errors)) if errors else float('nan'),
        'error_px_max': float(np.max(errors)) if errors else float('nan'),
        'seconds_median': float(np.median(seconds)) if seconds else float('nan'),
        'cpu_seconds': cpu,
        'tracked': tracked,
        'anchors_by_flow': anchors_by_flow,
        'width': width,
        'settings': settings,
    }
