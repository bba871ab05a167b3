"""``matrix-tracker train --site SITE``: a detector for one site, in one command.

The training and validation sequences are simulated sequences of the site (``simulate --site``'s code path,
:func:`matrix_core.sim.sequence.simulate`), each from its own seed; the training and validation seeds must
differ, so a seed used in neither stays free for a held-out test. Site datasets made beforehand
(``simulate --site`` or a user's annotated real frames in the site dataset format) may be added to either
split; each must be of the site: its area, and drones the site has. The BEV grid is the site's area and cell
(plus the recipe's margin). Training starts from a checkpoint's weights (fine-tuning: its network, trained
on another site's cells, is convolutional over any grid and any number of views) or from scratch, and the
recipe's model selection applies (``best.pt``: the epoch with the highest validation MODA).

Simulated sequences are written to ``DATA/<site>_<split>_s<seed>`` and reused when a finished one of the
same seed, frames, image scale and scene config is already there (a rerun or ``--resume`` does not simulate
again). Every checkpoint written records the site it was trained for (``site``: name, file, area, cell,
drones), which is what ``fuse`` and ``evaluate`` take it with.
"""

import dataclasses
import json
from dataclasses import dataclass, field
from pathlib import Path

from matrix_core.bev.config import SequenceSpec
from matrix_core.site import Site

SCRATCH = 'scratch'  # --init: no weights to start from
# SceneConfig fields a site replaces (sim/site_rig.scene_for_site); the others come from the scene config
SITE_SCENE_KEYS = ('name', 'area', 'block', 'pillars', 'boards', 'drones', 'building_distance')


@dataclass(frozen=True)
class SimulatedSequence:
    """One sequence ``train --site`` simulates (or finds already simulated) at ``folder``."""

    split: str  # 'train' or 'val'
    seed: int
    frames: int
    folder: Path


@dataclass
class SiteTrainingPlan:
    """What one ``train --site`` run trains on: the site, the sequences to simulate (or reuse), and the
    prepared datasets of each split."""

    site: Site
    sim_config: str
    image_scale: float
    simulated: list = field(default_factory=list)  # SimulatedSequence
    train_data: list = field(default_factory=list)  # Path of site datasets made beforehand
    val_data: list = field(default_factory=list)
    val_data_weight: float = 1.0  # of each val_data dataset in val_score

    def seeds(self, split: str) -> list:
        return [s.seed for s in self.simulated if s.split == split]

    def specs(self) -> tuple:
        """(train, val) lists of :class:`SequenceSpec` (ground-truth calibration, every frame)."""
        train = [SequenceSpec(str(s.folder)) for s in self.simulated if s.split == 'train']
        train += [SequenceSpec(str(p)) for p in self.train_data]
        val = [SequenceSpec(str(s.folder)) for s in self.simulated if s.split == 'val']
        val += [SequenceSpec(str(p), weight=self.val_data_weight) for p in self.val_data]
        return train, val

    def summary(self) -> list:
        """Lines saying what is trained on, the seeds of each split, and which seeds are free for a test."""
        lines = []
        for split, frames_of in (('training', 'train'), ('validation', 'val')):
            seqs = [s for s in self.simulated if s.split == frames_of]
            if seqs:
                seeds = ' '.join(str(s.seed) for s in seqs)
                frames = sorted({s.frames for s in seqs})
                lines.append(
                    f'{split} seeds {seeds}: {len(seqs)} simulated sequence(s) of {self.site.name} '
                    f'({self.sim_config}, {"/".join(map(str, frames))} frames each, image scale {self.image_scale:g})'
                )
        lines += [f'training dataset {p}' for p in self.train_data]
        lines += [f'validation dataset {p} (weight {self.val_data_weight:g})' for p in self.val_data]
        used = set(self.seeds('train')) | set(self.seeds('val'))
        free = next(s for s in range(201, 10**6) if s not in used)
        lines.append(f'held out: any other seed (e.g. simulate --site ... --seed {free}) is a test no run has seen')
        return lines


def plan_site_training(
    site: Site,
    data_dir,
    train_seeds,
    val_seeds,
    frames: int,
    val_frames: int,
    sim_config: str,
    image_scale: float,
    train_data=(),
    val_data=(),
    val_data_weight: float = 1.0,
) -> SiteTrainingPlan:
    """The plan of one run; ValueError when a seed is in both splits or twice in one, when no split has any
    sequence, or when a given dataset is not of ``site`` (:func:`check_site_dataset`)."""
    for split, seeds in (('--train-seeds', train_seeds), ('--val-seeds', val_seeds)):
        if len(set(seeds)) != len(seeds):
            raise ValueError(f'{split}: a seed is given twice: {list(seeds)}')
    both = sorted(set(train_seeds) & set(val_seeds))
    if both:
        raise ValueError(
            f'seeds {both} are in --train-seeds and --val-seeds: validation must be sequences not trained on'
        )
    if frames < 1 or val_frames < 1:
        raise ValueError(f'--frames and --val-frames must be >= 1, got {frames}, {val_frames}')
    data_dir = Path(data_dir)
    simulated = [
        SimulatedSequence(split, seed, n, data_dir / f'{site.name}_{split}_s{seed}')
        for split, seeds, n in (('train', train_seeds, frames), ('val', val_seeds, val_frames))
        for seed in seeds
    ]
    if not val_data_weight >= 0:
        raise ValueError(f'--val-data-weight must be >= 0, got {val_data_weight}')
    for what, paths in (('--train-data', train_data), ('--val-data', val_data)):
        for p in paths:
            check_site_dataset(p, site, what)
    plan = SiteTrainingPlan(
        site, sim_config, image_scale, simulated, list(map(Path, train_data)), list(map(Path, val_data)),
        val_data_weight,
    )  # fmt: skip
    train, _ = plan.specs()
    if not train:
        raise ValueError('nothing to train on: give --train-seeds or --train-data')
    return plan


def check_site_dataset(path, site: Site, what: str) -> None:
    """A dataset given to ``train --site``: it opens, its area is the site's and its drones are the site's
    (all or some); ValueError naming the folder, the flag and what differs."""
    from matrix_core.datasets import open_dataset

    ds = open_dataset(path)
    if any(abs(float(a) - float(b)) > 1e-6 for a, b in zip(ds.area, site.area)):
        raise ValueError(
            f'{what} {path}: its area {list(ds.area)} is not the area {list(site.area)} of site {site.name} '
            f'({site.path})'
        )
    unknown = [v for v in ds.views if v not in site.drone_names]
    if unknown:
        raise ValueError(
            f'{what} {path}: drones {unknown} are not drones of site {site.name} '
            f'(drones: {", ".join(site.drone_names)})'
        )
    if not ds.frames:
        raise ValueError(f'{what} {path}: no frame with every drone\'s image and calibration')


def simulate_settings(plan: SiteTrainingPlan, seq: SimulatedSequence):
    """The :class:`SimulateSettings` of one sequence: ``simulate --site`` with these flags, JPEG images."""
    from matrix_core.sim.settings import SimulateSettings

    return SimulateSettings(
        config=plan.sim_config,
        frames=seq.frames,
        seed=seq.seed,
        out=str(seq.folder),
        site=str(plan.site.path),
        image_scale=plan.image_scale,
        image_ext='.jpg',
    )


def finished_simulation(settings) -> bool:
    """Whether ``settings.out`` holds the finished simulation of these settings (seed, frames, image scale and
    scene config as recorded in its ``site_dataset.json`` and ``simulate_summary.json``); ValueError when the
    folder holds something else (an unfinished or different run), which is never overwritten."""
    from matrix_core.datasets.site_reader import META_FILE
    from matrix_core.sim.config import load_scene_config, scene_config_to_dict
    from matrix_core.sim.sequence import SUMMARY_FILE

    out = Path(settings.out)
    if not out.is_dir() or not any(out.iterdir()):
        return False
    try:
        meta = json.loads((out / META_FILE).read_text())['simulator']
        summary = json.loads((out / SUMMARY_FILE).read_text())
    except (OSError, ValueError, KeyError, TypeError):
        meta = summary = None
    done = bool(summary) and summary.get('frames_requested') == settings.frames and not summary.get('stopped')
    # the scene as recorded is the config with the site's geometry (sim/site_rig.scene_for_site): compare the rest
    scene = json.loads(json.dumps(scene_config_to_dict(load_scene_config(settings.config))))
    recorded = (meta or {}).get('config') or {}
    same = bool(meta) and (
        meta.get('seed') == settings.seed
        and meta.get('image_scale') == settings.image_scale
        and all(recorded.get(k) == v for k, v in scene.items() if k not in SITE_SCENE_KEYS)
    )
    if done and same:
        return True
    raise ValueError(
        f'{out} holds no finished simulation of seed {settings.seed} ({settings.frames} frames, image scale '
        f'{settings.image_scale:g}, config {settings.config}): remove it, or give another --data folder'
    )


def simulate_missing(plan: SiteTrainingPlan, log=print, progress: bool = True) -> None:
    """Simulate every planned sequence that is not already there (:func:`finished_simulation`)."""
    from matrix_core.sim.sequence import simulate

    for seq in plan.simulated:
        settings = simulate_settings(plan, seq)
        if finished_simulation(settings):
            log(f'{seq.split} seed {seq.seed}: reusing {seq.folder}')
            continue
        log(f'{seq.split} seed {seq.seed}: simulating {seq.frames} frames into {seq.folder}')
        simulate(settings, progress)


def site_record(site: Site) -> dict:
    """What a checkpoint records of the site it was trained for."""
    return {
        'name': site.name,
        'file': str(site.path),
        'area': [float(v) for v in site.area],
        'cell_m': float(site.cell_m),
        'drones': list(site.drone_names),
    }


def init_settings(init: str):
    """(checkpoint path, its :class:`BevSettings`) of ``--init`` (a path or a shipped checkpoint's name), or
    (None, None) for ``scratch``."""
    from matrix_core.bev.checkpoint import load_checkpoint
    from matrix_core.bev.settings import BevSettings
    from matrix_core.fusion.settings import resolve_checkpoint

    if init == SCRATCH:
        return None, None
    path = resolve_checkpoint(init)
    return path, BevSettings(**load_checkpoint(path)['settings'])


def site_bev_settings(recipe, site: Site, init_bev=None):
    """The recipe's :class:`BevSettings` on the site's grid (its area and cell); with an init checkpoint's
    settings, that checkpoint's network (model, temporal) so that its weights load."""
    changes = {'area': [float(v) for v in site.area], 'cell_m': float(site.cell_m)}
    if init_bev is not None:
        changes.update(model=init_bev.model, temporal=init_bev.temporal)
    return dataclasses.replace(recipe, **changes)
