"""How big each experiment run is: frames, resolution, epochs, seeds. ``quick`` is a smoke test,
``standard`` the size of docs/RESULTS.md (the default detector's recipe, one working session on the 2-core
machine), ``full`` the shipped complex model's recipe (many hours)."""

from dataclasses import dataclass, field, replace


@dataclass(frozen=True)
class ExperimentSize:
    """Every knob that sets the cost of a run (all steps depend on it, so it is part of their cache keys).

    Attributes:
        name: run folder name under ``--out``.
        smoke_test: the numbers only show that the pipeline runs (RESULTS.md says so loudly).
        train_frames / test_frames: simulated frames per variant (train and held-out test seeds differ).
        transfer_shares: shares of the modified variant's training frames of the transfer sweep (each trained
            from scratch and from the complex model); must hold the paper's 0.5 (``transfer_fraction``).
        sim_fast: simulate at 640x360 (else 1920x1080, the paper's size).
        image_width / image_height: network input (px); cell_m: BEV cell (m); model: registry name.
        epochs, lr, lr_schedule, batch_size, max_steps_per_epoch: training (0 steps: the whole set each epoch).
        augment: training augmentation (bev/augment.py) on, as in the default detector's recipe.
        seeds: training seeds of the run-to-run experiment (the first one is "the" model of the others).
        ransac_seeds: seeds of the registration's plain RANSAC, one registration run each on the complex
            test sequence with the main model (the paper's run-to-run variation).
        jobs: steps run at once (one torch thread each); 2 uses both cores of the 2-core machine.
        dropout_rates / dropout_seeds: camera dropout at test time (random view subsets per seed).
        expected_minutes: measured or estimated wall time with ``jobs`` steps at once (documented in RESULTS.md).
        notes: one line on the size; warning: a caveat printed at the top of RESULTS.md.
    """

    name: str
    smoke_test: bool
    train_frames: int
    test_frames: int
    transfer_shares: tuple = (0.05, 0.1, 0.25, 0.5)
    sim_fast: bool = True
    image_width: int = 320
    image_height: int = 176
    cell_m: float = 0.25
    model: str = 'bev_small'
    epochs: int = 8
    lr: float = 2e-3
    lr_schedule: str = 'cosine'
    batch_size: int = 1
    max_steps_per_epoch: int = 0
    augment: bool = False
    seeds: tuple = (0, 1, 2)
    ransac_seeds: tuple = tuple(range(10))
    dropout_rates: tuple = (0.0, 0.25, 0.5, 0.75)
    dropout_seeds: tuple = (0, 1, 2)
    jobs: int = 1
    expected_minutes: float = 0.0
    notes: str = field(default='', compare=False)
    warning: str = field(default='', compare=False)

    def __post_init__(self):
        if self.train_frames < 2 or self.test_frames < 2:
            raise ValueError('train_frames and test_frames must be >= 2')
        if not all(0 < f <= 1 for f in self.transfer_shares) or self.transfer_fraction not in self.transfer_shares:
            raise ValueError(
                f'transfer_shares must be in (0, 1] and hold {self.transfer_fraction}, got {self.transfer_shares}'
            )
        if len(self.seeds) < 1 or not self.dropout_rates or not self.ransac_seeds or self.jobs < 1:
            raise ValueError('need at least one training seed, RANSAC seed, dropout rate and job')

    # The paper's transfer share: the headline row of the transfer experiment.
    transfer_fraction = 0.5

    def frames_of_share(self, share: float) -> int:
        """Modified-variant training frames of a transfer share (at least 2)."""
        return max(2, round(self.train_frames * share))

    @property
    def transfer_frames(self) -> int:
        return self.frames_of_share(self.transfer_fraction)


QUICK = ExperimentSize(
    name='quick',
    smoke_test=True,
    train_frames=40,
    test_frames=12,
    image_width=160,
    image_height=96,
    cell_m=0.5,
    model='bev_tiny',
    epochs=5,
    lr=3e-3,
    transfer_shares=(0.25, 0.5),
    ransac_seeds=(0, 1),
    expected_minutes=10,  # 64 steps: 9.7 min wall (4 min CPU) on the 2-core machine under load, 2026-12-02
    notes='tiny sequences, 160x96 input, 0.5 m cells, 5 epochs: a smoke test of the whole pipeline',
)

# The recipe of the former checkpoints/complex.pt (bev/configs/complex.yaml: 500 frames, 480x272 input,
# 17 epochs, batch 2, cosine lr) for each of the 7 trainings: about 70 min per model on one thread of the
# machine that trained complex.pt (8 h in all), 9 min per epoch (2.5 h per model, about 18 h in all) on a
# 2-core AVX2 EPYC (measured 2026-12-01). The plan now trains about 2.8 more (simple_static and the transfer
# sweep), with two at once: roughly the same 18 h wall.
FULL = ExperimentSize(
    name='full',
    smoke_test=False,
    train_frames=500,
    test_frames=100,
    image_width=480,
    image_height=272,
    cell_m=0.25,
    model='bev_small',
    epochs=17,
    lr=2e-3,
    batch_size=2,
    seeds=(0, 1, 2),
    dropout_seeds=(0, 1, 2, 3, 4),
    jobs=2,
    expected_minutes=18 * 60,
    notes='the recipe of the shipped complex model (500 frames, 480x272 input, 0.25 m cells, 17 epochs)',
)

# A medium run (about 35 min on one thread) between the two: still far too small for the paper's numbers.
MEDIUM = replace(
    QUICK,
    name='medium',
    smoke_test=False,
    train_frames=240,
    test_frames=40,
    image_width=192,
    image_height=112,
    epochs=15,
    lr=2e-3,
    transfer_shares=(0.05, 0.1, 0.25, 0.5),
    ransac_seeds=(0, 1, 2),
    expected_minutes=35,
    notes='short sequences, 192x112 input, 0.5 m cells, 15 epochs: more than a smoke test, far from the paper',
    warning='REDUCED-SIZE RUN: short simulated sequences, low resolution and short CPU training. The '
    'numbers show the direction and rough size of the effects at best; single-sequence, '
    'few-seed results move by several points between runs.',
)

# The default detector's recipe (bev/configs/detector.yaml: bev_small, 320x176 input, 0.25 m cells, batch 1,
# lr 2e-3 cosine, augmentation; 600 frames x 8 epochs in about 40 min per training on one thread of this
# 2-core machine with two trainings at once, i.e. about 0.5 s per frame and epoch) on shorter sequences, so
# that the whole plan fits one working session with two steps at once: 8 + 1.8 (transfer sweep) trainings
# of 300 frames x 10 epochs = about 195 thread-minutes, plus simulation, 14 registration runs, 2 PnP runs
# and about 60 evaluations. Measured end to end on an idle 2-core machine (docs/RESULTS.md): 109.5 min wall,
# 218.5 min summed over the 89 steps (complex trainings about 28 min each, simple 15, evaluations 2-8 s).
STANDARD = ExperimentSize(
    name='standard',
    smoke_test=False,
    train_frames=300,
    test_frames=60,
    image_width=320,
    image_height=176,
    cell_m=0.25,
    model='bev_small',
    epochs=10,
    lr=2e-3,
    batch_size=1,
    augment=True,
    seeds=(0, 1, 2),
    dropout_seeds=(0, 1, 2),
    jobs=2,
    expected_minutes=110,
    notes="the default detector's recipe (320x176 input, 0.25 m cells, augmentation) on 300-frame sequences, "
    '10 epochs, two steps at once',
    warning='STANDARD-SIZE RUN: the default detector\'s input and cell size, but 300 training frames per variant '
    'and 10 CPU epochs (the paper trains 100 epochs on GPUs); single test sequences move MODA/MOTA by '
    'a few points.',
)

SIZES = {s.name: s for s in (QUICK, MEDIUM, STANDARD, FULL)}
