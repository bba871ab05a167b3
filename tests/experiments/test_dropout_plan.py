"""Camera-dropout subsets (seeded, exact rates) and the experiment plan built from them."""

import hashlib

import pytest

from matrix_core.experiments.dropout import dropout_subsets, dropped_count
from matrix_core.experiments.plan import VIEWS, build_plan, transfer_name
from matrix_core.experiments.sizes import QUICK, SIZES
from matrix_core.fusion.settings import DEFAULT_CHECKPOINT, shipped_checkpoint


@pytest.mark.parametrize('rate, dropped', [(0.0, 0), (0.25, 2), (0.5, 4), (0.75, 6)])
def test_subsets_drop_the_rate_of_the_views(rate, dropped):
    subsets = dropout_subsets(VIEWS, rate, seeds=range(10))
    assert len(subsets) == (1 if dropped == 0 else 10)
    for s in subsets:
        assert len(s.dropped) == dropped == dropped_count(rate, len(VIEWS))
        assert len(s.kept) == len(VIEWS) - dropped
        assert set(s.kept) | set(s.dropped) == set(VIEWS) and not set(s.kept) & set(s.dropped)
        assert list(s.kept) == [v for v in VIEWS if v in s.kept]  # original order kept


def test_subsets_are_seeded_and_random():
    a = dropout_subsets(VIEWS, 0.5, seeds=range(20))
    b = dropout_subsets(VIEWS, 0.5, seeds=range(20))
    assert a == b
    assert len({s.dropped for s in a}) > 10  # 70 possible subsets: seeds give different ones
    counts = {v: sum(v in s.dropped for s in dropout_subsets(VIEWS, 0.25, seeds=range(400))) for v in VIEWS}
    assert all(60 < c < 140 for c in counts.values()), counts  # each view dropped about 100 times of 400


def test_bad_rate_is_an_error():
    with pytest.raises(ValueError, match='drop rate'):
        dropout_subsets(VIEWS, 1.0, [0])


@pytest.mark.parametrize('name', sorted(SIZES))
def test_plan_has_every_experiment_once_and_in_order(name):
    size = SIZES[name]
    plan = build_plan(size)
    names = [s.name for s in plan]
    assert len(names) == len(set(names))
    position = {n: i for i, n in enumerate(names)}
    for s in plan:
        assert all(position[n] < position[s.name] for n in s.needs), s.name
    evals = [s.params for s in plan if s.kind == 'evaluate']
    # 4: one evaluation per (variant, rate > 0, seed) with exactly the rate's share of views dropped.
    for variant in ('simple', 'complex'):
        for rate in size.dropout_rates[1:]:
            runs = [e for e in evals if e['test'] == variant and e['drop_rate'] == rate]
            assert len(runs) == len(size.dropout_seeds)
            assert all(len(e['dropped']) == dropped_count(rate, 8) == 8 - len(e['views']) for e in runs)
    # 4: every training seed evaluated; 1: every calibration source on the main complex model.
    assert {e['model'] for e in evals if e['test'] == 'complex' and not e['dropped']} >= {
        f'complex_s{s}' for s in size.seeds
    } | {'complex_static'}
    assert {e['calibration'] for e in evals if e['model'] == f'complex_s{size.seeds[0]}'} == {
        'ground_truth',
        'pnp',
        'pnp_stale',
        'registration',
        'frozen_first',
        'reference',
    }
    # 1: the same sources on the simple variant, and static-trained baselines on both variants.
    assert {e['calibration'] for e in evals if e['model'] == 'simple_s0' and e['test'] == 'simple'} == {
        'ground_truth',
        'pnp',
        'pnp_stale',
        'registration',
        'frozen_first',
        'reference',
    }
    for variant in ('simple', 'complex'):
        assert any(
            e['model'] == f'{variant}_static' and e['test'] == variant and e['calibration'] == 'frozen_first'
            for e in evals
        )
        assert next(s for s in plan if s.name == f'train/{variant}_static').params['calibration'] == 'frozen_first'
    # 2: transfer starts from the main complex model and uses each share of the frames (the paper's 50 % too).
    assert 0.5 in size.transfer_shares
    for share in size.transfer_shares:
        scratch = next(s.params for s in plan if s.name == f'train/{transfer_name("scratch", share)}')
        transfer = next(s.params for s in plan if s.name == f'train/{transfer_name("transfer", share)}')
        assert transfer['init'] == f'train/complex_s{size.seeds[0]}' and scratch['init'] is None
        assert transfer['frames'] == scratch['frames'] == [0, size.frames_of_share(share) - 1]
    half = next(s.params for s in plan if s.name == 'train/modified_transfer_p50')
    assert half['frames'] == [0, size.transfer_frames - 1]
    # 4: one plain-RANSAC registration per RANSAC seed, each read by one evaluation of the main model.
    registers = {s.name: s.params for s in plan if s.kind == 'register'}
    for k in size.ransac_seeds:
        geometry = registers[f'geometry/complex_test_registration_ransac_s{k}']
        assert (geometry['estimator'], geometry['seed']) == ('ransac', k)
        [e] = [e for e in evals if e['ransac_seed'] == k]
        assert e['calibration_dir'] == f'geometry/complex_test_registration_ransac_s{k}'
        assert e['model'] == f'complex_s{size.seeds[0]}' and e['calibration'] == 'registration'
    # The live registration (MAGSAC, the default) on both test variants; 5: the MultiviewX readers.
    for variant in ('simple', 'complex'):
        assert registers[f'geometry/{variant}_test_registration']['estimator'] == 'magsac'
    assert any(s.kind == 'readers' and s.name == 'tables/multiviewx_sample' for s in plan)
    # 6: the shipped default detector through the live graph on the real sample, keyed by the checkpoint's bytes.
    [live] = [s for s in plan if s.kind == 'live_graph']
    assert live.name == 'tables/matrix_sample_live' and live.params['checkpoint'] == DEFAULT_CHECKPOINT
    assert live.params['checkpoint_sha256'] == hashlib.sha256(shipped_checkpoint().read_bytes()).hexdigest()


def test_quick_transfer_uses_half_the_frames():
    assert QUICK.transfer_frames == QUICK.train_frames // 2 == QUICK.frames_of_share(0.5)


def test_standard_size_is_the_default_detectors_recipe():
    import yaml

    from matrix_core.bev.config import CONFIG_DIR

    recipe = yaml.safe_load((CONFIG_DIR / 'detector.yaml').read_text())  # the default detector's recipe
    s = SIZES['standard']
    assert (s.model, s.image_width, s.image_height, s.cell_m) == (
        recipe['bev']['model'],
        recipe['bev']['image_width'],
        recipe['bev']['image_height'],
        recipe['bev']['cell_m'],
    )
    assert s.augment and s.jobs == 2 and not s.smoke_test and s.expected_minutes <= 150
    assert len(s.ransac_seeds) == 10 and s.transfer_shares == (0.05, 0.1, 0.25, 0.5)
