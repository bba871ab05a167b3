"""What each kind of step runs. ``EXECUTORS[kind](params, out, run_dir, progress, log)`` writes into ``out``
(those that run the network also take ``device``, a resolved ``matrix_core.device`` setting);
raises :class:`StepUnavailable` when this checkout lacks something the step needs (not an error of the run)."""

import inspect
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import torch

from matrix_core.reference_size import REFERENCE_WIDTH


class StepUnavailable(Exception):
    """The step cannot run in this checkout (e.g. a calibration source that does not exist yet)."""


def run_simulate(p: dict, out: Path, run_dir: Path, progress: bool, log) -> None:
    from matrix_core.sim.sequence import simulate
    from matrix_core.sim.settings import SimulateSettings

    simulate(
        SimulateSettings(
            config=p['config'],
            frames=p['frames'],
            seed=p['seed'],
            out=str(out),
            fast=p['fast'],
            image_ext=p['image_ext'],
        )
    )


def _cli(args: list, out: Path, log_name: str) -> None:
    """Run ``matrix-tracker ARGS`` in a child process on one thread; its output goes to ``out/log_name``."""
    env = {**os.environ, 'OMP_NUM_THREADS': '1', 'MKL_NUM_THREADS': '1', 'OPENBLAS_NUM_THREADS': '1'}
    out.mkdir(parents=True, exist_ok=True)
    with open(out / log_name, 'w') as f:
        rc = subprocess.run(
            [sys.executable, '-m', 'matrix_core.cli.main', *args], stdout=f, stderr=subprocess.STDOUT, env=env
        ).returncode
    if rc != 0:
        tail = (out / log_name).read_text()[-600:]
        raise RuntimeError(f'matrix-tracker {args[0]} exited with {rc}; end of {out / log_name}:\n{tail}')


def scaled_calib_config(variant: str, width: int, height: int, path: Path) -> Path:
    """The shipped calibration scene of a simulator variant (written for 1920x1080) with its intrinsics
    scaled to ``width`` x ``height`` (pixel-centre convention: c' = (c + 0.5) s - 0.5)."""
    import yaml

    from matrix_core.calib.scene import default_config_path

    scene = yaml.safe_load(default_config_path(f'sim_{variant}.yaml').read_text())
    (w0, h0), K = scene['image_size'], list(scene['intrinsics']['K'])
    sx, sy = width / w0, height / h0
    scene['intrinsics']['K'] = [
        K[0] * sx,
        K[1] * sx,
        (K[2] + 0.5) * sx - 0.5,
        0.0,
        K[4] * sy,
        (K[5] + 0.5) * sy - 0.5,
        0.0,
        0.0,
        1.0,
    ]
    scene['image_size'] = [width, height]
    path.write_text(yaml.safe_dump(scene, sort_keys=False))
    return path


def run_calibrate(p: dict, out: Path, run_dir: Path, progress: bool, log) -> None:
    out.mkdir(parents=True, exist_ok=True)
    # beside the step's folder, not in it: calibrate refuses an output folder that contains one of its inputs
    config = scaled_calib_config(p['variant'], *p['image_size'], out.with_name(f'{out.name}.calib_scene.yaml'))
    # --write-stale: the pnp_stale source uses the stale frames' last good poses (as the live node republishes them);
    # --overwrite: the folder holds the step's own log (_cli); the runner empties it before each run
    _cli(
        [
            'calibrate',
            str(run_dir / p['dataset']),
            '--out',
            str(out),
            '--config',
            str(config),
            '--compare',
            '--write-stale',
            '--overwrite',
        ],
        out,
        'calibrate.log',
    )


def run_register(p: dict, out: Path, run_dir: Path, progress: bool, log) -> None:
    # The registration defaults are tuned on 1920x1080 (scale 0.25 = 480x270): keep that working size.
    # estimator/seed: magsac (the live default) or one seeded plain-RANSAC run (run-to-run variation).
    scale = min(1.0, 0.25 * REFERENCE_WIDTH / p['image_size'][0])
    _cli(
        [
            'register',
            str(run_dir / p['dataset']),
            '--out',
            str(out),
            '--scale',
            f'{scale:g}',
            '--estimator',
            p.get('estimator', 'magsac'),
            '--registration_seed',
            str(p.get('seed', 0)),
        ],
        out,
        'register.log',
    )


def _sequence_spec(p: dict, run_dir: Path):
    from matrix_core.bev.config import SequenceSpec

    return SequenceSpec(str(run_dir / p['dataset']), list(p['frames']), p['calibration'])


def initialise_from(init_checkpoint: Path, config, out: Path) -> None:
    """Start a training run from another model's weights through the trainer's own resume: ``out/last.pt``
    gets those weights, a fresh optimizer, epoch 0 and the random state a run from scratch would have
    after building its model (so scratch and transfer differ only in the initial weights)."""
    from matrix_core.bev.checkpoint import load_checkpoint, save_checkpoint
    from matrix_core.bev.registry import build_model
    from matrix_core.bev.training import seed_everything

    ckpt = load_checkpoint(init_checkpoint)
    trained = ckpt['settings']
    if (trained['model'], trained.get('temporal', True)) != (config.bev.model, config.bev.temporal):
        raise ValueError(f'{init_checkpoint} is a {trained["model"]} model; this run trains {config.bev.model}')
    seed_everything(config.seed)
    model = build_model(config.bev.model, temporal=config.bev.temporal)
    rng = torch.get_rng_state()
    model.load_state_dict(ckpt['model'])
    optimizer = torch.optim.AdamW(model.parameters(), lr=config.lr, weight_decay=config.weight_decay)
    save_checkpoint(
        out / 'last.pt',
        model,
        config.bev,
        optimizer=optimizer.state_dict(),
        epoch=0,
        history=[],
        best=-math.inf,
        torch_rng=rng,
        initialised_from=str(init_checkpoint),
    )


def run_train(p: dict, out: Path, run_dir: Path, progress: bool, log, device: str) -> None:
    from matrix_core.bev.augment import AugmentConfig
    from matrix_core.bev.config import TrainConfig
    from matrix_core.bev.settings import BevSettings
    from matrix_core.bev.training import train

    config = TrainConfig(
        train=[_sequence_spec(p, run_dir)],
        bev=BevSettings(**p['bev']),
        epochs=p['epochs'],
        lr=p['lr'],
        lr_schedule=p['lr_schedule'],
        batch_size=p['batch_size'],
        seed=p['seed'],
        max_steps_per_epoch=p['max_steps_per_epoch'],
        num_threads=torch.get_num_threads(),
        augment=AugmentConfig(enabled=bool(p.get('augment', False))),
        out_dir=str(out),
    )
    if p['init'] and not (out / 'last.pt').is_file():
        out.mkdir(parents=True, exist_ok=True)
        initialise_from(run_dir / p['init'] / 'last.pt', config, out)
    train(config, out, resume=True, progress=progress, log=lambda msg: None, device=device)


def run_evaluate(p: dict, out: Path, run_dir: Path, progress: bool, log, device: str) -> None:
    from matrix_core.bev.calibration_sources import CALIBRATION_SOURCES
    from matrix_core.bev.checkpoint import load_model
    from matrix_core.bev.data import BevFrames
    from matrix_core.bev.evaluation import evaluate
    from matrix_core.bev.plots import save_trajectories_png
    from matrix_core.device import resolve_device

    if p['calibration'] not in CALIBRATION_SOURCES:
        raise StepUnavailable(
            f'calibration source {p["calibration"]!r} does not exist in this checkout '
            f'(known: {sorted(CALIBRATION_SOURCES)})'
        )
    kwargs = {}
    if p['calibration_dir']:
        if 'calibration_dir' not in inspect.signature(BevFrames).parameters:
            raise StepUnavailable('BevFrames takes no calibration_dir in this checkout')
        kwargs['calibration_dir'] = str(run_dir / p['calibration_dir'])
    start = time.perf_counter()
    model, settings = load_model(run_dir / p['checkpoint'])
    model = model.to(resolve_device(device))
    data = BevFrames(run_dir / p['dataset'], settings, None, p['calibration'], p['views'], False, **kwargs)
    result = evaluate(model, data, progress=False)
    train_params = json.loads((run_dir / 'steps' / (str(Path(p['checkpoint']).parent) + '.started.json')).read_text())
    record = {
        **p,
        'trained': train_params,
        'views_used': list(p['views'] or data.views),
        'detection': result.detection.as_dict(),
        'tracking': result.tracking.as_dict(),
        'hota': result.hota.as_dict(),
        'num_frames': len(data.frames),
        'eval_s': time.perf_counter() - start,
        'failures': result.failures_dict(),
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / 'metrics.json').write_text(json.dumps(record, indent=2))
    if p['plot']:
        save_trajectories_png(
            out / 'trajectories.png',
            result.gt,
            result.tracks,
            data.grid,
            f'{p["model"]} on the {p["test"]} test sequence ({p["calibration"]} calibration)',
        )


def run_readers(p: dict, out: Path, run_dir: Path, progress: bool, log) -> None:
    from matrix_core.experiments.table3 import foot_point_agreement, shared_path

    root = shared_path(p['dataset'])
    if not root.is_dir():
        raise StepUnavailable(f'{root} is missing (set MATRIX_SHARED to the shared data folder)')
    out.mkdir(parents=True, exist_ok=True)
    (out / 'metrics.json').write_text(json.dumps({**p, 'path': str(root), **foot_point_agreement(root)}, indent=2))


from matrix_core.experiments.real_live import run_live_real  # noqa: E402  (it imports StepUnavailable from here)

EXECUTORS = {
    'simulate': run_simulate,
    'calibrate': run_calibrate,
    'register': run_register,
    'train': run_train,
    'evaluate': run_evaluate,
    'readers': run_readers,
    'live_graph': run_live_real,
}
