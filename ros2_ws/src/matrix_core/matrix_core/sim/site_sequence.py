"""``simulate --site SITE``: render a site file's scene and write it as a site dataset
(:mod:`matrix_core.datasets.site_reader`).

The site gives the area (any size and origin), the drones (names, cameras, homes or reference poses:
:mod:`matrix_core.sim.site_rig`), the boards and the obstacles; ``--config`` gives the rest of the scene (crowd,
light, camera effects, distractors). The dataset's ``site.yaml`` is the site as simulated: cameras at the
rendered size, each drone's ``home`` and ``altitude_m`` where it flew, and references that are the rendered
reference images and their calibrations in the folder (``references.source: files``), so a site whose
references were ``simulate`` gets them here.
"""

from pathlib import Path

import numpy as np

from matrix_core.datasets.site_writer import SiteDatasetWriter
from matrix_core.sim.config import load_scene_config, scene_config_to_dict
from matrix_core.sim.sequence import Simulation, render_frame, run_frames, write_truth
from matrix_core.sim.site_rig import scene_for_site, site_rig
from matrix_core.site import load_site, site_path


def _floats(values) -> list:
    return [float(v) for v in np.asarray(values, dtype=float).ravel()]


def site_document(site, rig) -> dict:
    """The site file of the simulated dataset (without references: the writer adds them)."""
    drones = []
    for k, d in enumerate(site.drones):
        home = rig.homes[k]
        drones.append(
            {
                'name': d.name,
                'camera': {'image_size': list(rig.sizes[k]), 'K': _floats(rig.K[k]), 'dist': [0.0] * 5},
                'altitude_m': round(float(home[2]), 4),
                'home': [round(float(home[0]), 4), round(float(home[1]), 4)],
            }
        )
    boards = [
        {
            'name': b.name,
            'origin': _floats(b.origin),
            'square': float(b.square),
            'inner_corners': [b.nx, b.ny],
            'axis_i': _floats(b.axis_i),
            'axis_j': _floats(b.axis_j),
            'first_cell_light': bool(b.first_cell_light),
        }
        for b in site.boards
    ]
    obstacles = [{'name': o.name, 'footprint': _floats(o.footprint), 'height': float(o.height)} for o in site.obstacles]
    return {
        'version': 1,
        'name': site.name,
        'area': _floats(site.area),
        'cell_m': float(site.cell_m),
        'drones': drones,
        'boards': boards,
        'obstacles': obstacles,
    }


def write_site_frame(sim: Simulation, writer: SiteDatasetWriter, frame: int, out: Path):
    """Render one frame and write it in the site dataset format."""
    data = render_frame(sim)
    for view in sim.views:
        writer.write_image(view, frame, data.images[view])
        writer.write_camera(view, frame, data.cameras[view])
        writer.write_board_points(view, frame, *data.markers[view])
    writer.write_annotations(frame, data.positions, data.boxes)
    write_truth(out, frame, data)
    return data


def simulate_site(settings, progress: bool = True) -> Path:
    """Generate ``settings.frames`` frames of ``settings.site`` into ``settings.out`` (module docstring)."""
    from matrix_core.datasets import open_dataset

    out = Path(settings.out)
    site = load_site(site_path(settings.site))
    base = load_scene_config(settings.config)
    rig = site_rig(site, settings.image_scale, settings.ring_radius, settings.altitude or base.drones.altitude)
    config = scene_for_site(site, base, rig.homes)
    replay = open_dataset(settings.replay) if settings.replay else None
    width, height = (max(s[i] for s in rig.sizes) for i in (0, 1))
    sim = Simulation(config, settings.seed, width, height, replay, rig)
    meta = {
        'simulator': {
            'config': scene_config_to_dict(config),
            'seed': settings.seed,
            'frame_period': settings.frame_period,
            'replay': settings.replay or None,
            'site': str(site.path),
            'image_scale': settings.image_scale,
        },
    }
    writer = SiteDatasetWriter(out, site_document(site, rig), settings.image_ext, meta)
    writer.write_board_markers({int(i): p for i, p in zip(sim.scene.marker_ids, sim.scene.marker_xyz)})
    for k, view in enumerate(sim.views):
        cam, img = sim.render_reference(k)
        writer.write_reference(view, img, cam)
    run_frames(sim, settings, out, lambda frame: write_site_frame(sim, writer, frame, out), progress)
    return out
