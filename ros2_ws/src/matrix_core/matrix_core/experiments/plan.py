"""The paper's experiments (issues 8 and 16) as a list of cached steps (simulate, calibrate, register,
train, evaluate, readers). A step is pure data: its folder name, what it runs and every parameter its
output depends on.

Experiments (simulated MATRIX variants; models are named ``<trained on>_<what>``):
    1. simple and complex, the live pipeline: ``simple_s0`` / ``complex_s0`` on held-out test sequences of
       their variant with each geometry source: ``registration`` (``matrix-tracker register``, as the live
       graph computes it: the headline "ours" row), ``pnp`` / ``pnp_stale`` (per-frame calibration route),
       ``ground_truth`` (the simulator's calibration: "oracle geometry"), ``frozen_first`` and
       ``reference`` (static camera), plus ``<variant>_static``, trained and tested with the frozen
       first-frame calibration (the EarlyBird/TrackTacular setting). Both variants.
    2. transfer sweep: the modified variant with each share of its training frames, from scratch
       (``modified_scratch_p<percent>``) vs initialised with ``complex_s0`` (``modified_transfer_p<percent>``);
       ``complex_s0`` without fine-tuning for reference (oracle geometry: the detector is the subject).
    3. camera dropout: ``simple_s0`` and ``complex_s0`` with random view subsets per rate and seed (oracle geometry).
    4. run-to-run variation as the paper measures it: ``complex_s0`` with the homographies of one
       plain-RANSAC registration run per RANSAC seed; and ``complex_s<seed>`` per training seed
       (registration homographies) as a second table.
    5. Table III: the dataset readers on the real MultiviewX sample (``../shared/multiviewx_sample``).
    6. Real data: the shipped default detector through the live graph on the real MATRIX sample (frames 0-4,
       its real validation set; :mod:`matrix_core.experiments.real_live`).
"""

from dataclasses import dataclass, field

from matrix_core.experiments import real_live
from matrix_core.experiments.dropout import dropout_subsets
from matrix_core.experiments.sizes import ExperimentSize
from matrix_core.fusion.settings import DEFAULT_CHECKPOINT

VARIANTS = ('simple', 'complex', 'modified')
# Simulator seeds of the training and held-out test sequences (never equal).
SIM_SEEDS = {'simple': (101, 201), 'complex': (102, 202), 'modified': (103, 203)}
VIEWS = ('D1', 'D2', 'D3', 'D4', 'D5', 'D6', 'D7', 'D8')  # the simulator's eight drones
# Test variants whose geometry is estimated (registration, PnP), and the steps that do it (name -> kind).
GEOMETRY_VARIANTS = ('simple', 'complex')
GEOMETRY_STEPS = {'pnp': 'calibrate', 'registration': 'register'}
# Calibration sources that read a geometry step's output folder (source -> step name suffix).
SOURCE_DIRS = {'pnp': 'pnp', 'pnp_stale': 'pnp', 'registration': 'registration'}
# Every geometry source of experiment 1, the headline (live pipeline) first.
ABLATION_SOURCES = ('registration', 'pnp', 'pnp_stale', 'ground_truth', 'frozen_first', 'reference')
HEADLINE_SOURCE = 'registration'
ORACLE_SOURCE = 'ground_truth'
MULTIVIEWX_STEP = 'tables/multiviewx_sample'


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
    return Step(
        f'data/{variant}_{role}',
        'simulate',
        {'config': variant, 'frames': frames, 'seed': seed, 'fast': size.sim_fast, 'image_ext': '.jpg'},
    )


def train_step(
    name: str,
    variant: str,
    size: ExperimentSize,
    seed: int = 0,
    calibration: str = 'ground_truth',
    frames: int = None,
    init: str = None,
) -> Step:
    data = f'data/{variant}_train'
    bev = {
        'model': size.model,
        'image_width': size.image_width,
        'image_height': size.image_height,
        'cell_m': size.cell_m,
    }
    params = {
        'variant': variant,
        'dataset': data,
        'frames': [0, (frames or size.train_frames) - 1],
        'calibration': calibration,
        'bev': bev,
        'epochs': size.epochs,
        'lr': size.lr,
        'lr_schedule': size.lr_schedule,
        'batch_size': size.batch_size,
        'seed': seed,
        'max_steps_per_epoch': size.max_steps_per_epoch,
        'augment': size.augment,
        'init': f'train/{init}' if init else None,
    }
    return Step(f'train/{name}', 'train', params, (data,) + ((f'train/{init}',) if init else ()))


def geometry_dir(variant: str, source: str, ransac_seed: int = None) -> str:
    """Folder of the geometry step a calibration source reads (``ransac_seed``: one plain-RANSAC run)."""
    suffix = f'_ransac_s{ransac_seed}' if ransac_seed is not None else ''
    return f'geometry/{variant}_test_{SOURCE_DIRS[source]}{suffix}'


def geometry_step(variant: str, kind: str, size: ExperimentSize, ransac_seed: int = None) -> Step:
    """PnP calibration (``calibrate``) or registration (``register``; MAGSAC, the live default, or plain
    RANSAC with ``ransac_seed``) of a variant's test sequence."""
    params = {'dataset': f'data/{variant}_test', 'variant': variant, 'image_size': sim_size(size)}
    source = 'pnp' if kind == 'calibrate' else 'registration'
    if kind == 'register':
        params.update(
            estimator='magsac' if ransac_seed is None else 'ransac', seed=0 if ransac_seed is None else int(ransac_seed)
        )
    return Step(geometry_dir(variant, source, ransac_seed), kind, params, (f'data/{variant}_test',))


def transfer_name(kind: str, share: float) -> str:
    """``modified_scratch_p50`` / ``modified_transfer_p5`` (kind: scratch or transfer; share in (0, 1])."""
    return f'modified_{kind}_p{100 * share:g}'


def eval_step(
    model: str,
    variant: str,
    calibration: str = 'ground_truth',
    subset=None,
    plot: bool = False,
    ransac_seed: int = None,
) -> Step:
    data = f'data/{variant}_test'
    name = f'eval/{model}__{variant}__{calibration}'
    needs = [data, f'train/{model}']
    params = {
        'model': model,
        'test': variant,
        'dataset': data,
        'checkpoint': f'train/{model}/last.pt',
        'calibration': calibration,
        'calibration_dir': None,
        'ransac_seed': ransac_seed,
        'views': None,
        'dropped': [],
        'drop_rate': 0.0,
        'drop_seed': -1,
        'plot': plot,
    }
    if ransac_seed is not None and calibration != 'registration':
        raise ValueError('a RANSAC seed only applies to the registration source')
    if calibration in SOURCE_DIRS:
        params['calibration_dir'] = geometry_dir(variant, calibration, ransac_seed)
        needs.append(params['calibration_dir'])
    if ransac_seed is not None:
        name += f'__ransac_s{ransac_seed}'
    if subset is not None and subset.dropped:
        name += f'__drop{subset.rate:g}_s{subset.seed}'
        params.update(
            views=list(subset.kept), dropped=list(subset.dropped), drop_rate=subset.rate, drop_seed=subset.seed
        )
    return Step(name, 'evaluate', params, tuple(needs))


def build_plan(size: ExperimentSize) -> list:
    """Every step of the experiments, each after the steps it needs, without duplicates."""
    steps = [data_step(v, role, size) for v in VARIANTS for role in ('train', 'test')]
    for variant in GEOMETRY_VARIANTS:
        steps += [geometry_step(variant, kind, size) for kind in GEOMETRY_STEPS.values()]
    steps += [geometry_step('complex', 'register', size, ransac_seed=k) for k in size.ransac_seeds]
    steps.append(Step(MULTIVIEWX_STEP, 'readers', {'dataset': 'shared:multiviewx_sample'}))
    steps.append(Step(real_live.STEP, 'live_graph', real_live.step_params(DEFAULT_CHECKPOINT)))
    first = size.seeds[0]
    main = f'complex_s{first}'
    steps.append(train_step('simple_s0', 'simple', size, seed=first))
    steps += [train_step(f'complex_s{s}', 'complex', size, seed=s) for s in size.seeds]
    for variant in GEOMETRY_VARIANTS:
        steps.append(train_step(f'{variant}_static', variant, size, seed=first, calibration='frozen_first'))
    # Smallest shares first: a partial run still shows the low-data regime, where pretraining matters most.
    for share in sorted(size.transfer_shares):
        frames = size.frames_of_share(share)
        steps.append(train_step(transfer_name('scratch', share), 'modified', size, seed=first, frames=frames))
        steps.append(
            train_step(transfer_name('transfer', share), 'modified', size, seed=first, frames=frames, init=main)
        )
    # 1: every geometry source on both variants, the static-trained models with their frozen calibration.
    for variant, model in (('simple', 'simple_s0'), ('complex', main)):
        steps += [
            eval_step(model, variant, source, plot=source in (HEADLINE_SOURCE, ORACLE_SOURCE))
            for source in ABLATION_SOURCES
        ]
        steps.append(eval_step(f'{variant}_static', variant, 'frozen_first'))
    # 4: RANSAC seeds of the registration with the main model; training seeds with the live geometry.
    steps += [eval_step(main, 'complex', 'registration', ransac_seed=k) for k in size.ransac_seeds]
    steps += [eval_step(f'complex_s{s}', 'complex', HEADLINE_SOURCE) for s in size.seeds]
    # 2: transfer sweep.
    steps += [
        eval_step(transfer_name(kind, share), 'modified')
        for share in sorted(size.transfer_shares)
        for kind in ('scratch', 'transfer')
    ]
    steps.append(eval_step(main, 'modified'))
    # 3: dropout (rate 0 is the plain oracle evaluation above).
    for model, variant in (('simple_s0', 'simple'), (main, 'complex')):
        for rate in size.dropout_rates:
            steps += [
                eval_step(model, variant, subset=s)
                for s in dropout_subsets(VIEWS, rate, size.dropout_seeds)
                if s.dropped
            ]
    unique = {}
    for s in steps:
        unique.setdefault(s.name, s)
    return list(unique.values())
