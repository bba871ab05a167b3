"""How big each experiment run is: frames, resolution, epochs, seeds. ``quick`` is a smoke test,
``full`` the size meant to give meaningful numbers."""

from dataclasses import dataclass, field, replace


@dataclass(frozen=True)
class ExperimentSize:
    """Every knob that sets the cost of a run (all steps depend on it, so it is part of their cache keys).

    Attributes:
        name: run folder name under ``--out``.
        smoke_test: the numbers only show that the pipeline runs (RESULTS.md says so loudly).
        train_frames / test_frames: simulated frames per variant (train and held-out test seeds differ).
        transfer_fraction: share of the modified variant's training frames used in the transfer experiment.
        sim_fast: simulate at 640x360 (else 1920x1080, the paper's size).
        image_width / image_height: network input (px); cell_m: BEV cell (m); model: registry name.
        epochs, lr, lr_schedule, batch_size, max_steps_per_epoch: training (0 steps: the whole set each epoch).
        seeds: training seeds of the run-to-run experiment (the first one is "the" model of the others).
        dropout_rates / dropout_seeds: camera dropout at test time (random view subsets per seed).
        expected_minutes: measured or estimated wall time on one CPU thread (documented in RESULTS.md).
        notes: one line on the size; warning: a caveat printed at the top of RESULTS.md.
    """

    name: str
    smoke_test: bool
    train_frames: int
    test_frames: int
    transfer_fraction: float = 0.5
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
    seeds: tuple = (0, 1, 2)
    dropout_rates: tuple = (0.0, 0.25, 0.5, 0.75)
    dropout_seeds: tuple = (0, 1, 2)
    expected_minutes: float = 0.0
    notes: str = field(default='', compare=False)
    warning: str = field(default='', compare=False)

    def __post_init__(self):
        if self.train_frames < 2 or self.test_frames < 2:
            raise ValueError('train_frames and test_frames must be >= 2')
        if not 0 < self.transfer_fraction <= 1:
            raise ValueError(f'transfer_fraction must be in (0, 1], got {self.transfer_fraction}')
        if len(self.seeds) < 1 or not self.dropout_rates:
            raise ValueError('need at least one training seed and one dropout rate')

    @property
    def transfer_frames(self) -> int:
        return max(2, round(self.train_frames * self.transfer_fraction))


QUICK = ExperimentSize(
    name='quick', smoke_test=True, train_frames=40, test_frames=12, image_width=160, image_height=96,
    cell_m=0.5, model='bev_tiny', epochs=5, lr=3e-3, expected_minutes=4,
    notes='tiny sequences, 160x96 input, 0.5 m cells, 5 epochs: a smoke test of the whole pipeline')

# The recipe of the shipped checkpoints/complex.pt (bev/configs/complex.yaml: 500 frames, 480x272 input,
# 17 epochs, batch 2, cosine lr) for each of the 7 trainings: about 70 min per model on one thread of the
# machine that trained complex.pt (8 h in all), 9 min per epoch (2.5 h per model, about 18 h in all) on a
# 2-core AVX2 EPYC (measured 2026-12-01).
FULL = ExperimentSize(
    name='full', smoke_test=False, train_frames=500, test_frames=100, image_width=480, image_height=272,
    cell_m=0.25, model='bev_small', epochs=17, lr=2e-3, batch_size=2, seeds=(0, 1, 2),
    dropout_seeds=(0, 1, 2, 3, 4), expected_minutes=18 * 60,
    notes='the recipe of the shipped complex model (500 frames, 480x272 input, 0.25 m cells, 17 epochs)')

# A medium run (about 35 min on one thread) between the two: still far too small for the paper's numbers.
MEDIUM = replace(QUICK, name='medium', smoke_test=False, train_frames=240, test_frames=40, image_width=192,
                 image_height=112, epochs=15, lr=2e-3, expected_minutes=35,
                 notes='short sequences, 192x112 input, 0.5 m cells, 15 epochs: more than a smoke test, far '
                       'from the paper',
                 warning='REDUCED-SIZE RUN: short simulated sequences, low resolution and short CPU training. The '
                         'numbers show the direction and rough size of the effects at best; single-sequence, '
                         'few-seed results move by several points between runs.')

SIZES = {s.name: s for s in (QUICK, MEDIUM, FULL)}
