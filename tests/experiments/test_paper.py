"""The paper table in code matches the MATRIX paper's figures, value by value
(written out here independently; '~' = approximate, '>' = bound, as the paper states them)."""

import pytest

from matrix_core.experiments import paper
from matrix_core.experiments.paper import Figure

# Table III (MODA, MODP, MOTA, MOTP; None = not given), Wildtrack then MultiviewX.
TABLE_III = {
    'MVTT': ((94.1, 81.3, None, None), (95.0, 92.8, None, None)),
    'MVDet': ((88.2, 75.7, None, None), (83.9, 79.6, None, None)),
    'MVDeTr': ((91.5, 82.1, None, None), (93.7, 91.3, None, None)),
    'EarlyBird': ((91.2, 81.8, 89.5, 86.6), (94.2, 90.1, 88.4, 86.2)),
    'TrackTacular': ((91.8, 79.8, 89.6, 81.7), (95.9, 89.2, 91.4, 86.7)),
    'REMP': ((90.9, 79.4, 88.5, 86.8), (89.9, 90.5, 81.0, 85.8)),
    'proposed': ((91.2, 79.7, 89.7, 81.2), (93.0, 90.3, 90.7, 86.7)),
}


def test_table_iii_is_the_papers():
    assert list(paper.STATIONARY) == list(TABLE_III)
    for method, (wildtrack, multiviewx) in TABLE_III.items():
        for dataset, values in (('Wildtrack', wildtrack), ('MultiviewX', multiviewx)):
            got = paper.STATIONARY[method][dataset]
            want = {k: Figure(v) for k, v in zip(('MODA', 'MODP', 'MOTA', 'MOTP'), values) if v is not None}
            assert got == want, (method, dataset)
            assert [str(got[k]) for k in want] == [f'{v:.1f}' for v in values if v is not None]  # 95.0, 81.0


def test_moving_drone_figures_are_the_papers():
    assert {k: {m: str(f) for m, f in v.items()} for k, v in paper.SIMPLE.items()} == {
        'EarlyBird': {'MODA': '94', 'recall': '95.9'},
        'TrackTacular': {'MOTA': '92.7', 'IDF1': '79.64'},
    }
    assert 'marginally lower' in paper.SIMPLE_PROPOSED_NOTE
    assert paper.COMPLEX == {
        'TrackTacular': {'MODA': Figure(5.72), 'MOTA': Figure(31.44), 'MT': Figure(0)},
        'proposed': {
            'MODA': Figure(89, '~'),
            'MOTA': Figure(88.5, '~'),
            'precision': Figure(97, '~'),
            'recall': Figure(86, '~'),
            'MT': Figure(80, '~'),
        },
    }
    assert paper.VARIANTS == {'simple': paper.SIMPLE, 'complex': paper.COMPLEX}


def test_transfer_dropout_and_runs_are_the_papers():
    assert paper.TRANSFER_SHARE == 0.5
    assert paper.TRANSFER == {
        'scratch': {'MODA': Figure(54, '~'), 'MODP': Figure(80, '>')},
        'pretrained': {'MODA': Figure(69, '~'), 'MODP': Figure(80, '>')},
    }
    assert 'relatively similar' in paper.TRANSFER_NOTE
    assert paper.DROPOUT == {
        ('simple', 'MODA'): {0.25: Figure(80, '>'), 0.75: Figure(45, '~')},
        ('complex', 'MODA'): {0.25: Figure(80, '>'), 0.75: Figure(36, '~')},
        ('complex', 'MOTA'): {0.25: Figure(80, '>'), 0.75: Figure(40, '~')},
        ('simple', 'MOTA'): {0.75: Figure(60, '~')},
    }
    assert paper.DROPOUT_MOTP_RANGE == (75.0, 85.0) and 'relatively stable' in paper.DROPOUT_MODP_NOTE
    assert (paper.EPOCHS, paper.RUNS) == (100, 10) and 'RANSAC' in paper.RUNS_VARY


@pytest.mark.parametrize(
    'figure, text',
    [
        (Figure(89, '~'), '~89'),
        (Figure(80, '>'), '>80'),
        (Figure(5.72), '5.72'),
        (Figure(79.64), '79.64'),
        (Figure(94), '94'),
    ],
)
def test_figures_print_as_the_paper_writes_them(figure, text):
    assert str(figure) == text
