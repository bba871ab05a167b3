"""Errors of estimated cameras against reference cameras (stored calibration or simulator truth)."""

import numpy as np

from matrix_core.calib.status import CalibStatus
from matrix_core.geometry.camera import Camera, rotation_angle_deg


def pose_errors(estimated: Camera, truth: Camera) -> tuple:
    """(rotation error in degrees, camera-centre error in metres)."""
    return rotation_angle_deg(estimated.R, truth.R), float(np.linalg.norm(estimated.center - truth.center))


def summarize_errors(rows: list) -> dict:
    """Summary of ``rows`` of dicts with 'status' (:class:`CalibStatus`), 'rot_err_deg', 'centre_err_m' (ok rows
    only)."""
    ok = [r for r in rows if r['status'] is CalibStatus.OK]
    rot = np.array([r['rot_err_deg'] for r in ok])
    ctr = np.array([r['centre_err_m'] for r in ok])
    out = {
        'frames': len(rows),
        'ok': len(ok),
        'stale': sum(r['status'] is CalibStatus.STALE for r in rows),
        'failed': sum(r['status'] is CalibStatus.FAILED for r in rows),
    }
    if len(ok):
        out.update(
            rot_median_deg=float(np.median(rot)),
            rot_max_deg=float(rot.max()),
            centre_median_m=float(np.median(ctr)),
            centre_max_m=float(ctr.max()),
        )
    return out
