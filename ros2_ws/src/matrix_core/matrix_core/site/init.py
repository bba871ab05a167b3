"""``matrix-tracker site init``: a site file from a user's recording and a boards description.

For each drone of the recording (a rosbag2 with ``<drone>/image_raw`` or ``<drone>/image/compressed`` and a
``<drone>/camera_info`` or ``<drone>/ground_truth/camera_info``; or a folder of images per drone with the
intrinsics given) the frames considered are calibrated from the boards (``matrix_core.calib``: the board
search around a pose prior, PnP, the plausibility checks); the frame with the most board corners (then the
lowest reprojection error) becomes the drone's reference. Its image, its calibration (``camera_yaml``) and the
site file are written to a new folder. A drone that saw no board, or has no pose prior, is left out with the
reason; the others are written.

The pose prior a drone's search starts from, first found wins: ``priors.<drone>`` in the boards description
(``position`` of the camera and a ground point it ``look_at``, metres, rough: a few metres off is enough),
else the pose in the recording's camera_info (``p = K [R | t]``, e.g. from the drone's navigation).
"""

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from matrix_core.calib.drone_calibrator import DroneCalibrator
from matrix_core.calib.scene import CalibScene
from matrix_core.calib.settings import CalibSettings
from matrix_core.calib.status import CalibStatus
from matrix_core.geometry.camera import Camera, pose_matrix
from matrix_core.settings import read_yaml
from matrix_core.site.load import SiteError, site_from_dict

BOARDS_KEYS = ('name', 'area', 'cell_m', 'boards', 'obstacles', 'priors')
_PRIOR_KEYS = ('position', 'look_at')
DEFAULT_CELL_M = 0.25  # the shipped detectors' cell (matrix_core.fusion.settings.MATRIX_CELL_M)
IMAGE_SUFFIXES = ('.png', '.jpg', '.jpeg', '.bmp')


@dataclass
class SiteDraft:
    """What the boards description gives: the site file's keys except the drones, and the pose priors."""

    data: dict  # name, area, cell_m, boards, obstacles (site file form)
    priors: dict = field(default_factory=dict)  # drone -> (position (3,), look_at (3,))
    drones: dict = field(default_factory=dict)  # drone -> its entry of a site file being completed
    boards: tuple = ()  # the boards, as Checkerboards (validated by the site loader)


def look_at_camera(K, dist, size, position, target) -> Camera:
    """The camera at ``position`` looking at ``target`` (world metres), image x level with the ground."""
    c, target = np.asarray(position, float), np.asarray(target, float)
    z = target - c
    if np.linalg.norm(z) < 1e-6 or np.linalg.norm(np.cross(z, [0.0, 0.0, 1.0])) < 1e-6 * np.linalg.norm(z):
        raise ValueError(f'look_at {list(target)} must lie away from position {list(c)}, not straight below it')
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 0.0, 1.0])
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z])
    return Camera(K, pose_matrix(R, -R @ c), int(size[0]), int(size[1]), dist)


def read_boards(path) -> SiteDraft:
    """The boards description at ``path``: a YAML with ``area`` and ``boards`` (the site file's board format),
    optionally ``name``, ``cell_m``, ``obstacles``, ``priors``; or an existing site file to complete (its
    drones' cameras are the intrinsics of an image folder). SiteError naming the file and the key."""
    path = Path(path)
    data = read_yaml(path)
    if 'version' in data:  # a site file: checked by the site loader as it stands
        site = site_from_dict(data, path)
        drones = {d['name']: d for d in data['drones']}
        keep = {k: data[k] for k in ('name', 'area', 'cell_m', 'boards', 'obstacles') if k in data}
        return SiteDraft(keep, {}, drones, site.boards)
    unknown = sorted(str(k) for k in data if k not in BOARDS_KEYS)
    if unknown:
        raise SiteError(f'{path}: unknown key(s) {", ".join(map(repr, unknown))} (allowed: {", ".join(BOARDS_KEYS)})')
    for key in ('area', 'boards'):
        if key not in data:
            raise SiteError(f'{path}: missing {key!r} (a boards description has {", ".join(BOARDS_KEYS)})')
    keep = {'name': data.get('name', path.stem), 'area': data['area'], 'cell_m': data.get('cell_m', DEFAULT_CELL_M)}
    keep.update({k: data[k] for k in ('boards', 'obstacles') if k in data})
    # The site loader checks the boards (format, inside the area) with a stand-in drone.
    stand_in = {'name': 'check', 'camera': {'image_size': [2, 2], 'K': [1, 0, 0.5, 0, 1, 0.5, 0, 0, 1]}}
    site = site_from_dict({'version': 1, **keep, 'references': {'source': 'simulate'}, 'drones': [stand_in]}, path)
    if not site.boards:
        raise SiteError(f'{path}: boards: none; the drones are calibrated from at least one checkerboard')
    priors = {}
    for drone, prior in (data.get('priors') or {}).items():
        where = f'{path}: priors.{drone}'
        if not isinstance(prior, dict) or sorted(prior) != sorted(_PRIOR_KEYS):
            raise SiteError(f'{where}: expected {{position: [x, y, z], look_at: [x, y, z]}} (metres), got {prior!r}')
        try:
            values = [np.asarray(prior[k], float).reshape(3) for k in _PRIOR_KEYS]
        except (TypeError, ValueError):
            raise SiteError(f'{where}: position and look_at are 3 numbers each, got {prior!r}') from None
        if not all(np.all(np.isfinite(v)) for v in values):
            raise SiteError(f'{where}: position and look_at must be finite, got {prior!r}')
        priors[str(drone)] = tuple(values)
    return SiteDraft(keep, priors, {}, site.boards)


@dataclass
class DroneFrames:
    """A drone's frames to consider: (H, W, 3) BGR images and the camera each was recorded with (its K, dist
    and size are the drone's intrinsics; its pose a prior when it is not the identity), and each frame's header
    stamp in seconds (None for an image folder)."""

    images: list = field(default_factory=list)
    cameras: list = field(default_factory=list)
    stamps: list = field(default_factory=list)


def _has_pose(camera: Camera) -> bool:
    """A camera_info pose that says something: not ``p = K [I | 0]`` (a camera_info without extrinsics)."""
    return not np.allclose(camera.cam_T_world, np.eye(4))


def frames_from_bag(bag, max_frames: int) -> dict:
    """drone -> :class:`DroneFrames` of a recording, at most ``max_frames`` frames each, spread over it."""
    from matrix_core.bags.reader import bag_topics, read_sequence_frames
    from matrix_core.site.parameter import recorded_drones

    counts = bag_topics(bag)
    drones = recorded_drones(counts)
    n = max((c for t, (_, c) in counts.items() if 'image' in t), default=0)
    step = max(1, math.ceil(n / max_frames))
    out = {d: DroneFrames() for d in drones}
    for k, frame in enumerate(read_sequence_frames(bag)):
        if k % step:
            continue
        for drone, image in frame.images.items():
            if drone in out and drone in frame.cameras and len(out[drone].images) < max_frames:
                out[drone].images.append(image)
                out[drone].cameras.append(frame.cameras[drone])
                out[drone].stamps.append(frame.stamp_ns * 1e-9)
    return out


def frames_from_folder(folder, intrinsics: dict, max_frames: int) -> dict:
    """drone -> :class:`DroneFrames` of ``folder/<drone>/*.png|jpg``, with ``intrinsics`` (drone -> its site
    file ``camera`` entry: image_size, K, dist) as each frame's camera; a drone without intrinsics is a
    SiteError naming it."""
    from matrix_core.datasets.base import read_image

    out = {}
    for sub in sorted(p for p in Path(folder).iterdir() if p.is_dir()):
        files = sorted(p for p in sub.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        if not files:
            continue
        if sub.name not in intrinsics:
            raise SiteError(f'{folder}: drone {sub.name} has images but no intrinsics (give its camera)')
        cam = intrinsics[sub.name]
        camera = Camera(
            np.asarray(cam['K'], float).reshape(3, 3),
            np.eye(4),
            int(cam['image_size'][0]),
            int(cam['image_size'][1]),
            list(cam.get('dist', [0.0] * 5)) + [0.0] * (5 - len(cam.get('dist', [0.0] * 5))),
        )
        step = max(1, math.ceil(len(files) / max_frames))
        frames = DroneFrames()
        for f in files[::step][:max_frames]:
            frames.images.append(read_image(f))
            frames.cameras.append(camera)
            frames.stamps.append(None)
        out[sub.name] = frames
    return out


@dataclass
class DroneReference:
    """A drone's outcome: ``camera`` and ``image`` of its chosen frame, or ``reason`` it was left out."""

    drone: str
    camera: Camera = None
    image: np.ndarray = None
    frame: int = -1
    stamp_s: float = None  # the chosen frame's header stamp, None for an image folder
    rms_px: float = float('nan')
    corners: int = 0
    reason: str = ''
    prior: str = ''


PRIOR_ROLLS_DEG = (0.0, 1.5, -1.5, 3.0, -3.0)  # the roll a position + look_at prior cannot give (its image x is level)


def _rolled(camera: Camera):
    """``camera`` turned about its optical axis by each of :data:`PRIOR_ROLLS_DEG`."""
    for deg in PRIOR_ROLLS_DEG:
        a = np.radians(deg)
        Rz = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        R = Rz @ camera.R
        yield Camera(camera.K, pose_matrix(R, -R @ camera.center), camera.width, camera.height, camera.dist)


def _ok(result) -> bool:
    """A fresh pose from this image (the calibrator's status ok)."""
    return result.camera is not None and result.status is CalibStatus.OK


def calibrate_drone(drone: str, frames: DroneFrames, boards: list, prior: tuple = None) -> DroneReference:
    """The best-calibrated frame of one drone (most board corners, then the lowest reprojection error)."""
    if not frames.images:
        return DroneReference(drone, reason='no frame with both an image and a camera_info')
    best, reasons = None, []
    for k, (image, rec) in enumerate(zip(frames.images, frames.cameras)):
        size = (image.shape[1], image.shape[0])
        if size != (rec.width, rec.height):
            reasons.append(f'frame {k}: image {size[0]}x{size[1]}, camera_info {rec.width}x{rec.height}')
            continue
        if prior is not None:
            start, how = look_at_camera(rec.K, rec.dist, size, *prior), 'priors in the boards description'
        elif _has_pose(rec):
            start, how = rec, "the recording's camera_info pose"
        else:
            return DroneReference(
                drone, reason='no pose prior: give priors.<drone> (position, look_at) in the boards description'
            )
        scene = CalibScene(list(boards), rec.K, rec.dist, size)
        result = None
        for rolled in _rolled(start):  # a rough prior is also off in roll: the board search needs it within ~1 deg
            result = DroneCalibrator(scene, CalibSettings(), rolled).process(image, 0.0)
            if _ok(result):
                break
        if not _ok(result):
            reasons.append(f'frame {k}: {result.message or result.status}')
            continue
        if best is None or (result.corners, -result.rms_px) > (best.corners, -best.rms_px):
            stamp = frames.stamps[k] if k < len(frames.stamps) else None
            best = DroneReference(drone, result.camera, image, k, stamp, result.rms_px, result.corners, prior=how)
    if best is None:
        return DroneReference(drone, reason='saw no board: ' + ('; '.join(reasons[:3]) or 'no frame'))
    return best


def camera_files(camera: Camera) -> tuple:
    """(intrinsic, extrinsic) mappings of the ``camera_yaml`` calibration format (internal conventions)."""
    intrinsic = {
        'image_size': [int(camera.width), int(camera.height)],
        'K': [float(v) for v in camera.K.ravel()],
        'dist': [float(v) for v in camera.dist.ravel()],
    }
    extrinsic = {'cam_T_world': [[float(v) for v in row] for row in camera.cam_T_world]}
    return intrinsic, extrinsic


def site_document(draft: SiteDraft, references: list) -> dict:
    """The site file of the drones that have a reference (``references/<drone>.png`` and its calibration)."""
    drones = []
    for ref in references:
        intrinsic, _ = camera_files(ref.camera)
        entry = {k: v for k, v in draft.drones.get(ref.drone, {}).items() if k in ('altitude_m', 'home')}
        drones.append(
            {
                'name': ref.drone,
                'camera': {k: intrinsic[k] for k in ('image_size', 'K', 'dist')},
                **entry,
                'reference': {
                    'image': f'references/{ref.drone}.png',
                    'calibration': {
                        'format': 'camera_yaml',
                        'intrinsic': f'references/{ref.drone}_intrinsic.yaml',
                        'extrinsic': f'references/{ref.drone}_extrinsic.yaml',
                    },
                    **({'stamp_s': float(ref.stamp_s)} if ref.stamp_s is not None else {}),
                },
            }
        )
    return {'version': 1, **draft.data, 'references': {'source': 'files', 'root': '.'}, 'drones': drones}


def write_site(out, draft: SiteDraft, references: list) -> Path:
    """Write the references and ``site.yaml`` into the new folder ``out`` (all or nothing); returns the site
    file's path."""
    import cv2

    from matrix_core.output_paths import atomic_folder

    out = Path(out)
    if out.is_dir() and not any(out.iterdir()):
        out.rmdir()  # an empty folder given as --out: filled as a new one
    with atomic_folder(out) as work:
        (work / 'references').mkdir(parents=True)
        for ref in references:
            if not cv2.imwrite(str(work / 'references' / f'{ref.drone}.png'), ref.image):
                raise OSError(f'could not write the reference image of {ref.drone}')
            intrinsic, extrinsic = camera_files(ref.camera)
            for name, data in (('intrinsic', intrinsic), ('extrinsic', extrinsic)):
                text = yaml.safe_dump(data, sort_keys=False)
                (work / 'references' / f'{ref.drone}_{name}.yaml').write_text(text)
        header = '# Written by matrix-tracker site init (docs/site-file.md); every position in internal metres.\n'
        (work / 'site.yaml').write_text(header + yaml.safe_dump(site_document(draft, references), sort_keys=False))
    return out / 'site.yaml'
