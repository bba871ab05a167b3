"""Warming a process up for live registration: the first registration a process runs pays for first calls
(OpenCV's SIFT, optical flow and homography fits, BLAS, regular expressions compiled and modules imported on
first use). In a live graph every drone process would pay them on its first frame, all at once, on a computer
that the first frame already loads most (docs/registration.md)."""

from dataclasses import replace

import cv2

from matrix_core.register.registrar import Registrar

_warmed = []  # the process has warmed up once (a module-level flag: the first calls are per process)


def warm_up_once(settings, reference_image, reference_camera, area, backend=None) -> list:
    """Register a drone's reference image to itself with a throwaway :class:`Registrar`: an anchor by features
    (SIFT, matching, robust fit) and then a frame tracked by flow, each as the live path calls them (a grey
    image, as ``matrix_ros.drone_link`` decodes it). Nothing is kept. Only the process's first call does
    anything: it returns the two registrations, later calls []. ``settings``: the live
    :class:`RegisterSettings`; the rest as :class:`Registrar` takes them."""
    if _warmed:
        return []
    _warmed.append(True)
    grey = cv2.cvtColor(reference_image, cv2.COLOR_BGR2GRAY) if reference_image.ndim == 3 else reference_image
    registrar = Registrar(
        replace(settings, mode='track', anchor_by_flow=False),
        reference_image,
        reference_camera,
        area,
        'warm-up',
        backend,
    )
    return [registrar.register(grey, frame) for frame in range(2)]
