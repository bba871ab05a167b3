"""Training configuration (YAML) for ``matrix-tracker train``; see ``configs/*.yaml``."""

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path


from matrix_core.bev.augment import AugmentConfig
from matrix_core.bev.settings import BevSettings
from matrix_core.settings import read_yaml
from matrix_core.tracking.settings import TrackerSettings

CONFIG_DIR = Path(__file__).resolve().parent / 'configs'


@dataclass
class SequenceSpec:
    """One MATRIX folder and the frames and calibration source to use from it."""

    path: str
    frames: list = None  # [first, last] inclusive, or None for all
    calibration: str = 'ground_truth'
    views: list = None  # None: all views
    calibration_dir: str = None  # output of matrix-tracker calibrate/register (pnp/registration sources)
    weight: float = 1.0  # validation only: its weight in the checkpoint-selection score (val_score)

    def __post_init__(self):
        if not self.weight >= 0:
            raise ValueError(f'{self.path}: weight must be >= 0, got {self.weight}')

    @property
    def label(self) -> str:
        """Short name of the sequence in logs: its folder name."""
        return Path(self.path).name

    def frame_list(self, available) -> list:
        if self.frames is None:
            return list(available)
        first, last = self.frames
        return [f for f in available if first <= f <= last]


@dataclass
class TrainConfig:
    train: list
    val: list = field(default_factory=list)
    bev: BevSettings = field(default_factory=BevSettings)
    tracker: TrackerSettings = field(default_factory=TrackerSettings)
    epochs: int = 10
    max_steps_per_epoch: int = 0  # 0: the whole training set
    batch_size: int = 1
    lr: float = 1e-3
    lr_schedule: str = 'constant'  # 'constant' or 'cosine' (per step, down to lr_min_ratio * lr at the end)
    lr_min_ratio: float = 0.02
    weight_decay: float = 1e-4
    # Offsets are L1 in metres and sub-cell targets lie within +-cell/2 (0.125 m): with weight 1 the offset
    # head sat at 0 (the median of its targets) until the heatmap had converged (overfitting 2 frames at
    # 0.25 m cells: L1 0.061 m after 60 steps vs 0.030 m with weight 10), i.e. never in a short run.
    loss_weights: dict = field(default_factory=lambda: {'heatmap': 1.0, 'offset': 10.0, 'tracking': 2.0})
    view_dropout: float = 0.15  # probability of dropping each view in a training sample
    augment: AugmentConfig = field(default_factory=AugmentConfig)  # training images only; off by default
    min_views: int = 4
    seed: int = 0
    # A checkpoint (path) whose weights training starts from (fine-tuning); its model and temporal setting must
    # be the config's ``bev`` ones. Empty: from scratch. A resumed run continues from last.pt instead.
    init: str = ''
    num_threads: int = 1
    validate_every: int = 1  # epochs
    out_dir: str = 'out/train'
    cache_images: bool = True
    # Weight averaging (bev/averaging.py): after the last epoch, the mean of the weights of the last
    # ``average_epochs`` epochs, batch-norm statistics measured again over ``bn_samples`` training samples,
    # validated like an epoch (``averaged.pt``; it becomes best.pt when its val_score is the highest). 0: off.
    average_epochs: int = 0
    bn_samples: int = 200

    def __post_init__(self):
        if not self.train:
            raise ValueError('config: "train" needs at least one sequence')
        if self.epochs < 1 or self.batch_size < 1 or not self.lr > 0:
            raise ValueError('config: epochs and batch_size must be >= 1 and lr > 0')
        if self.lr_schedule not in ('constant', 'cosine'):
            raise ValueError(f'config: lr_schedule must be constant or cosine, got {self.lr_schedule!r}')
        unknown = set(self.loss_weights) - {'heatmap', 'offset', 'tracking'}
        if unknown:
            raise ValueError(f'config: unknown loss_weights {sorted(unknown)}; allowed heatmap, offset, tracking')
        if not 0 <= self.average_epochs <= self.epochs or self.bn_samples < 1:
            raise ValueError(
                f'config: average_epochs must be in [0, epochs] and bn_samples >= 1, got '
                f'{self.average_epochs}, {self.bn_samples}'
            )
        if not 0 <= self.view_dropout < 1:
            raise ValueError(f'config: view_dropout must be in [0, 1), got {self.view_dropout}')


def resolve_config_path(name_or_path) -> Path:
    """A YAML path, or the name of a shipped config (``configs/<name>.yaml``)."""
    p = Path(name_or_path)
    if p.is_file():
        return p
    shipped = CONFIG_DIR / f'{name_or_path}.yaml'
    if shipped.is_file():
        return shipped
    known = sorted(q.stem for q in CONFIG_DIR.glob('*.yaml'))
    raise FileNotFoundError(f'no config file {p} and no shipped config named {name_or_path!r} (shipped: {known})')


# Keys whose value is a mapping of settings: a config that names a ``base`` changes only the entries it gives.
NESTED_KEYS = ('bev', 'tracker', 'augment', 'loss_weights')


def _read_raw(name_or_path, seen=()) -> tuple:
    """(path, raw dict) of a config, with its ``base`` (a config name or path) read first and overridden."""
    path = resolve_config_path(name_or_path)
    if path in seen:
        raise ValueError(f'{path}: its base configs form a loop')
    raw = read_yaml(path)
    base = raw.pop('base', None)
    if base is None:
        return path, raw
    merged = _read_raw(base, (*seen, path))[1]
    for key, value in raw.items():
        nested = key in NESTED_KEYS and isinstance(value, dict) and isinstance(merged.get(key), dict)
        merged[key] = {**merged[key], **value} if nested else value
    return path, merged


def load_config(name_or_path, overrides: dict = None) -> TrainConfig:
    """Read a YAML config; unknown keys are errors (a typo must not be silently ignored). ``base: NAME`` starts
    from another config (see NESTED_KEYS)."""
    path, raw = _read_raw(name_or_path)
    raw.update(overrides or {})
    names = {f.name for f in dataclasses.fields(TrainConfig)}
    unknown = set(raw) - names
    if unknown:
        raise ValueError(f'{path}: unknown keys {sorted(unknown)}; allowed: {sorted(names)}')
    try:
        raw['train'] = [SequenceSpec(**s) for s in raw.get('train') or []]
        raw['val'] = [SequenceSpec(**s) for s in raw.get('val') or []]
        raw['bev'] = BevSettings(**(raw.get('bev') or {}))
        raw['tracker'] = TrackerSettings(**(raw.get('tracker') or {}))
        raw['augment'] = AugmentConfig(**(raw.get('augment') or {}))
        return TrainConfig(**raw)
    except TypeError as exc:
        raise ValueError(f'{path}: {exc}') from None
