"""Generate a sequence: step crowd and drones, render every view, write MATRIX files (+ optional bag).

Output folder layout: the MATRIX format written by :class:`~matrix_core.datasets.MatrixWriter`
(``image_subsets``, ``calibrations``, ``annotations_positions``, ``matchings/{Pedestrians,Planes}``,
``reference/`` = each drone's static reference pose, empty scene), plus simulator-only truth in the internal
convention:
``sim_ground_truth/TTTT.json`` (per view: ``img_H_ground``, ``world_T_cam``, camera centre, drone position
and velocity) and, with ``bag``, ``bag/`` (rosbag2 MCAP, topics in :mod:`matrix_core.bags`).

No frame ends the run: a frame whose step, rendering or writing raises is left out (its files deleted, so no
reader sees half a frame; the bag holds only whole frames) and the sequence goes on, one time step further.
``simulate_summary.json`` says how many frames were written and which failed, and why; the bag is closed on
any exit (an error, Ctrl-C), so every frame written before stays readable.

Checkerboard inner corners are the markers of ``matchings/Planes/3d.txt`` (ids in
:data:`~matrix_core.sim.scene.BOARD_MARKER_BASE`); each frame's ``CameraN_2d`` lists those inside the image
and not hidden by a box (people may stand on them).
"""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from matrix_core.datasets import MatrixWriter
from matrix_core.datasets.matrix_conventions import view_name, world_to_position_id
from matrix_core.datasets.types import PersonAnnotation
from matrix_core.reference_size import REFERENCE_WIDTH
from matrix_core.sim.appearance import person_looks
from matrix_core.sim.camera_effects import CameraEffects
from matrix_core.sim.config import check_matrix_grid, load_scene_config, scene_config_to_dict
from matrix_core.sim.crowd import Crowd, ReplayCrowd
from matrix_core.sim.drones import DroneFleet
from matrix_core.sim.ground_truth import annotation_box, view_truth, visible_markers
from matrix_core.sim.person_model import gait_phase, swing_amplitude
from matrix_core.sim.lighting import sample_lighting
from matrix_core.sim.render import People, Renderer
from matrix_core.sim.scene import Scene
from matrix_core.sim.visibility import line_of_sight, rays_blocked


def ground_m_per_px(width: int) -> float:
    """Ground texel size for a render width: 2.5 cm at 1920 px, proportionally coarser below."""
    return 0.025 * max(1.0, REFERENCE_WIDTH / width)


class Simulation:
    """The moving scene of one config and seed, independent of the render size.

    The random streams of scene, crowd, drones and looks are separate children of ``seed``, so e.g.
    rendering at another resolution or replaying trajectories does not change the drone motion. ``rig``: a
    site's drones (:class:`~matrix_core.sim.drones.DroneRig`; views named after them, their own cameras), or
    None for the MATRIX ring D1..D8 rendered at ``width`` x ``height``.
    """

    def __init__(self, config, seed: int, width: int, height: int, replay=None, rig=None):
        self.config = config
        self.width, self.height = width, height
        seqs = np.random.SeedSequence(seed).spawn(6)
        scene_rng, crowd_rng, drone_rng, look_rng = (np.random.default_rng(s) for s in seqs[:4])
        light_seq, effects_seq = seqs[5].spawn(2)  # child 5: lighting and camera effects
        # child 4: distractors, ground materials and facade styles
        self.scene = Scene(config, scene_rng, ground_m_per_px(width), np.random.default_rng(seqs[4]))
        self.renderer = Renderer(self.scene, sample_lighting(config.lighting, np.random.default_rng(light_seq)))
        if replay is not None:
            self.crowd = ReplayCrowd(replay, crowd_rng, config.crowd.height_range)
        else:
            self.crowd = Crowd(self.scene.crowd_config(), crowd_rng)  # distractors in the area are obstacles
        self.fleet = DroneFleet(config.drones, config.center, drone_rng, rig)
        self.colors, self.dress = person_looks(look_rng, len(self.crowd.ids), config.crowd.dress_fraction)
        self.views = [view_name(k + 1) for k in range(config.drones.count)] if rig is None else list(rig.names)
        self.effects = CameraEffects(config.camera_effects, len(self.views), effects_seq)

    def step(self, seconds: float) -> None:
        self.crowd.step(seconds)
        self.fleet.step(seconds)

    def people(self) -> People:
        c = self.config.crowd
        cr = self.crowd
        return People(
            cr.ids,
            cr.positions,
            cr.heights,
            self.colors,
            c.leg_radius,
            c.body_radius,
            cr.headings,
            gait_phase(cr.walked, cr.heights, cr.ids),
            swing_amplitude(cr.speeds) if c.walking_pose else None,
            self.dress,
        )

    def positions(self) -> dict:
        """person id -> (3,) foot point, metres."""
        return {int(i): np.array([p[0], p[1], 0.0]) for i, p in zip(self.crowd.ids, self.crowd.positions)}

    def camera(self, k: int):
        return self.fleet.camera(k, self.width, self.height)

    def render_reference(self, k: int) -> tuple:
        """(camera, image) of drone ``k``'s static reference pose: the empty scene, same camera effects."""
        cam = self.fleet.reference_camera(k, self.width, self.height)
        return cam, self.effects.render(self.renderer, cam, None, k)[0]

    def render_view(self, k: int) -> tuple:
        """(camera, image, ids, visible (N,) bool) of view index ``k`` now, through drone ``k``'s camera
        effects (one call = one frame of that camera)."""
        cam = self.camera(k)
        img, ids = self.effects.render(self.renderer, cam, self.people(), k)
        visible = line_of_sight(cam, self.crowd.positions, self.scene.occluders)
        return cam, img, ids, visible


@dataclass
class FrameTruth:
    """One rendered frame and its ground truth, in the internal convention, before any file format.

    Attributes:
        images: view -> (H, W, 3) BGR uint8; cameras: view -> Camera.
        positions: person id -> (3,) foot point, metres (every person, seen or not).
        boxes: person id -> {view: BoundingBox} for the views that see the person.
        seen: view -> {person id: (3,) metres} of the persons that view sees (line of sight).
        markers: view -> ((M,) board marker ids, (M, 2) pixels) of the board corners it sees.
        truth: view -> :func:`~matrix_core.sim.ground_truth.view_truth` (``sim_ground_truth/TTTT.json``).
    """

    images: dict
    cameras: dict
    positions: dict
    boxes: dict
    seen: dict
    markers: dict
    truth: dict


def render_frame(sim: Simulation) -> FrameTruth:
    """Render every view of the simulation's current state (in view order: each call is one frame of every
    camera's effects)."""
    images, cameras, truth, seen_by, markers = {}, {}, {}, {}, {}
    boxes = {int(i): {} for i in sim.crowd.ids}
    positions = sim.positions()
    for k, view in enumerate(sim.views):
        cam, img, _, visible = sim.render_view(k)
        images[view], cameras[view] = img, cam
        seen = {}
        for pid, xy, vis in zip(sim.crowd.ids, sim.crowd.positions, visible):
            if vis:
                boxes[int(pid)][view] = annotation_box(cam, xy)
                seen[int(pid)] = positions[int(pid)]
        seen_by[view] = seen
        markers[view] = visible_markers(
            cam, sim.scene.marker_ids, sim.scene.marker_xyz, sim.scene.occluders, rays_blocked
        )
        truth[view] = view_truth(cam, sim.fleet.drones[k])
    return FrameTruth(images, cameras, positions, boxes, seen_by, markers, truth)


def write_truth(out: Path, frame: int, data: FrameTruth) -> None:
    """``sim_ground_truth/TTTT.json``: the simulator-only truth of every view (module docstring)."""
    path = out / 'sim_ground_truth' / f'{frame:04d}.json'
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data.truth, indent=1, sort_keys=True) + '\n')


def write_frame(sim: Simulation, writer: MatrixWriter, frame: int, out: Path) -> FrameTruth:
    """Render one frame and write it in the MATRIX format."""
    data = render_frame(sim)
    for view in sim.views:
        writer.write_image(view, frame, data.images[view])
        writer.write_camera(view, frame, data.cameras[view])
        writer.write_line_of_sight(view, frame, data.seen[view])
        writer.write_plane_points(view, frame, *data.markers[view])
    positions = data.positions
    persons = [
        PersonAnnotation(pid, world_to_position_id(positions[pid][:2]), positions[pid][:2], data.boxes[pid])
        for pid in sorted(positions)
    ]
    writer.write_annotations(frame, persons, sim.views)
    writer.write_pedestrians(frame, positions)
    write_truth(out, frame, data)
    return data


def simulate(settings, progress: bool = True) -> Path:
    """Generate ``settings.frames`` frames into ``settings.out`` (see the module docstring); with
    ``settings.site``, a site dataset of that site (:mod:`matrix_core.sim.site_sequence`)."""
    from matrix_core.datasets import open_dataset

    out = Path(settings.out)
    if out.exists() and any(out.iterdir()):
        raise ValueError(f'output folder {out} is not empty')
    if settings.site_dataset:
        from matrix_core.sim.site_sequence import simulate_site

        return simulate_site(settings, progress)
    config = load_scene_config(settings.config)
    check_matrix_grid(config.area)
    replay = open_dataset(settings.replay) if settings.replay else None
    sim = Simulation(config, settings.seed, settings.width, settings.height, replay)
    meta = {
        'simulator': {
            'config': scene_config_to_dict(config),
            'seed': settings.seed,
            'frame_period': settings.frame_period,
            'replay': settings.replay or None,
        },
        'image_size': [settings.width, settings.height],
    }
    writer = MatrixWriter(out, area=tuple(config.area), image_ext=settings.image_ext, extra_meta=meta)
    writer.write_plane_markers({int(i): p for i, p in zip(sim.scene.marker_ids, sim.scene.marker_xyz)})
    for k, view in enumerate(sim.views):
        cam, img = sim.render_reference(k)
        writer.write_image(view, 0, img, reference=True)
        writer.write_camera(view, 0, cam, reference=True)
    run_frames(sim, settings, out, lambda frame: write_frame(sim, writer, frame, out), progress)
    return out


def run_frames(sim: Simulation, settings, out: Path, write, progress: bool = True) -> None:
    """Step, render and write ``settings.frames`` frames with ``write(frame) -> FrameTruth`` (and into
    ``out/bag`` with ``settings.bag``); a frame that raises is left out (its files removed) and the run goes
    on; ``simulate_summary.json`` is written on any exit."""
    from tqdm import tqdm

    from matrix_core.bags import SequenceBagWriter, SequenceClock

    clock = SequenceClock(settings.start_time, settings.frame_period)
    bag = SequenceBagWriter(out / 'bag', sim.views, settings.compressed, clock) if settings.bag else None
    if bag is not None:
        bag.__enter__()
    failed, written, stopped = {}, [], 'interrupted'
    name = sim.config.name
    try:
        for frame in tqdm(range(settings.frames), desc=f'simulate {name}', unit='frame', disable=not progress):
            try:
                if frame > 0:
                    sim.step(settings.frame_period)
                data = write(frame)
                if bag is not None:
                    bag.write_frame(frame, data.images, data.cameras, data.positions)
                written.append(frame)
            except Exception as exc:  # one frame's failure: that frame is left out, the sequence goes on
                failed[frame] = f'{type(exc).__name__}: {exc}'
                remove_frame_files(out, frame)
                tqdm.write(f'simulate: frame {frame} failed: {failed[frame]}')
        stopped = ''
    finally:
        if bag is not None:
            bag.__exit__(None, None, None)  # closed on any exit: the frames written stay readable
        write_summary(out, settings.frames, written, failed, stopped)


SUMMARY_FILE = 'simulate_summary.json'


def write_summary(out: Path, requested: int, written: list, failed: dict, stopped: str = '') -> dict:
    """``OUT/simulate_summary.json``: frames requested and written, each failed frame with its reason, and
    ``stopped`` ('interrupted' when the run ended before its last frame)."""
    summary = {
        'frames_requested': requested,
        'frames_written': len(written),
        'frames_failed': len(failed),
        'failed_frames': [{'frame': f, 'reason': r} for f, r in sorted(failed.items())],
        'stopped': stopped,
        'last_frame_written': written[-1] if written else None,
    }
    (out / SUMMARY_FILE).write_text(json.dumps(summary, indent=1) + '\n')
    return summary


def remove_frame_files(out: Path, frame: int) -> None:
    """Delete what a failed frame had written of itself (files named ``TTTT.*`` or ``*_TTTT.*`` outside
    ``reference/`` and ``bag/``), so that no reader takes a half-written frame (images of some drones,
    annotations missing) for a whole one."""
    tag = f'{frame:04d}'
    for path in out.rglob('*'):
        rel = path.relative_to(out).parts
        if (
            path.is_file()
            and rel[0] not in ('reference', 'bag')
            and (path.stem == tag or path.stem.endswith('_' + tag))
        ):
            path.unlink()
