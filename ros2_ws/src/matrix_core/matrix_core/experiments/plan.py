"""The five experiments of issue 8 as a list of cached steps (simulate, calibrate, register, train,
evaluate). A step is pure data: its folder name, what it runs and every parameter its output depends on.

Experiments (all on simulated MATRIX variants; models are named ``<trained on>_<what>``):
    1. simple vs complex: ``simple_s0`` and ``complex_s0`` on held-out test sequences of their variant.
    2. static baselines and ablations on the complex test sequence with ``complex_s0``: calibration
       sources ground_truth (ours), pnp / pnp_stale (registration off), registration (calibration off), frozen_first
       and reference (both off: the static-camera assumption), plus ``complex_static``, a model trained and
       tested with the frozen first-frame calibration (the EarlyBird/TrackTacular setting).
    3. transfer: the modified variant with ``transfer_fraction`` of its training frames, from scratch
       (``modified_scratch``) vs initialised with ``complex_s0`` (``modified_transfer``); ``complex_s0``
       without fine-tuning for reference.
    4. camera dropout: ``simple_s0`` and ``complex_s0`` with random view subsets per rate and seed.
    5. run-to-run variation: ``complex_s<seed>`` for every training seed.
"""

from dataclasses import dataclass, field

from matrix_core.experiments.dropout import dropout_subsets
from matrix_core.experiments.sizes import ExperimentSize

VARIANTS = ('simple', 'complex', 'modified')
# Simulator seeds of the training and held-out test sequences (never equal).
SIM_SEEDS = {'simple': (101, 201), 'complex': (102, 202), 'modified': (103, 203)}
VIEWS = ('D1', 'D2', 'D3', 'D4', 'D5', 'D6', 'D7', 'D8')   # the simulator's eight drones
# Steps that estimate the geometry of a test sequence (name -> kind), and the calibration sources that
# read their output folder (source -> step name).
GEOMETRY_STEPS = {'pnp': 'calibrate', 'registration': 'register'}
SOURCE_DIRS = {'pnp': 'pnp', 'pnp_stale': 'pnp', 'registration': 'registration'}
ABLATION_SOURCES = ('ground_truth', 'pnp', 'pnp_stale', 'registration', 'frozen_first', 'reference')


@dataclass(frozen=True)
class Step:
    """``name`` is also the step's folder under the run folder; ``params`` (JSON) is its cache key;
    paths inside ``params`` are relative to the run folder; ``needs`` are names of earlier steps."""

    name: str
    kind: str
    params: dict
    needs: tuple = field(default=())


def sim_size(size: ExperimentSize) -> list:
    """[width, height] of the simulated images."""
    return [640, 360] if size.sim_fast else [1920, 1080]


def data_step(variant: str, role: str, size: ExperimentSize) -> Step:
    seed = SIM_SEEDS[variant][0 if role == 'train' else 1]
    frames = size.train_frames if role == 'train' else size.test_frames
    return Step(f'data/{variant}_{role}', 'simulate',
                {'config': variant, 'frames': frames, 'seed': seed, 'fast': size.sim_fast, 'image_ext': '.jpg'})


def train_step(name: str, variant: str, size: ExperimentSize, seed: int = 0, calibration: str = 'ground_truth',
               frames: int = None, init: str = None) -> Step:
    data = f'data/{variant}_train'
    bev = {'model': size.model, 'image_width': size.image_width, 'image_height': size.image_height,
           'cell_m': size.cell_m}
    params = {'variant': variant, 'dataset': data, 'frames': [0, (frames or size.train_frames) - 1],
              'calibration': calibration, 'bev': bev, 'epochs': size.epochs, 'lr': size.lr,
              'lr_schedule': size.lr_schedule, 'batch_size': size.batch_size, 'seed': seed,
              'max_steps_per_epoch': size.max_steps_per_epoch, 'init': f'train/{init}' if init else None}
    return Step(f'train/{name}', 'train', params, (data,) + ((f'train/{init}',) if init else ()))


def eval_step(model: str, variant: str, calibration: str = 'ground_truth', subset=None, plot: bool = False) -> Step:
    data = f'data/{variant}_test'
    name = f'eval/{model}__{variant}__{calibration}'
    needs = [data, f'train/{model}']
    params = {'model': model, 'test': variant, 'dataset': data, 'checkpoint': f'train/{model}/last.pt',
              'calibration': calibration, 'calibration_dir': None, 'views': None, 'dropped': [],
              'drop_rate': 0.0, 'drop_seed': -1, 'plot': plot}
    if calibration in SOURCE_DIRS:
        params['calibration_dir'] = f'geometry/{variant}_test_{SOURCE_DIRS[calibration]}'
        needs.append(params['calibration_dir'])
    if subset is not None and subset.dropped:
        name += f'__drop{subset.rate:g}_s{subset.seed}'
        params.update(views=list(subset.kept), dropped=list(subset.dropped), drop_rate=subset.rate,
                      drop_seed=subset.seed)
    return Step(name, 'evaluate', params, tuple(needs))


def build_plan(size: ExperimentSize) -> list:
    """Every step of the five experiments, each after the steps it needs, without duplicates."""
    steps = [data_step(v, role, size) for v in VARIANTS for role in ('train', 'test')]
    for source, kind in GEOMETRY_STEPS.items():
        steps.append(Step(f'geometry/complex_test_{source}', kind,
                          {'dataset': 'data/complex_test', 'variant': 'complex', 'image_size': sim_size(size)},
                          ('data/complex_test',)))
    steps.append(train_step('simple_s0', 'simple', size, seed=size.seeds[0]))
    steps += [train_step(f'complex_s{s}', 'complex', size, seed=s) for s in size.seeds]
    main = f'complex_s{size.seeds[0]}'
    steps.append(train_step('complex_static', 'complex', size, seed=size.seeds[0], calibration='frozen_first'))
    steps.append(train_step('modified_scratch', 'modified', size, seed=size.seeds[0], frames=size.transfer_frames))
    steps.append(train_step('modified_transfer', 'modified', size, seed=size.seeds[0], frames=size.transfer_frames,
                            init=main))
    # 1 and 5: every model of its own variant with the ground-truth per-frame calibration.
    steps.append(eval_step('simple_s0', 'simple', plot=True))
    steps += [eval_step(f'complex_s{s}', 'complex', plot=s == size.seeds[0]) for s in size.seeds]
    # 2: ablations and static baselines.
    steps += [eval_step(main, 'complex', source) for source in ABLATION_SOURCES if source != 'ground_truth']
    steps.append(eval_step('complex_static', 'complex', 'frozen_first'))
    # 3: transfer.
    steps += [eval_step(m, 'modified') for m in ('modified_scratch', 'modified_transfer', main)]
    # 4: dropout (rate 0 is the plain evaluation above).
    for model, variant in (('simple_s0', 'simple'), (main, 'complex')):
        for rate in size.dropout_rates:
            steps += [eval_step(model, variant, subset=s) for s in dropout_subsets(VIEWS, rate, size.dropout_seeds)
                      if s.dropped]
    unique = {}
    for s in steps:
        unique.setdefault(s.name, s)
    return list(unique.values())
