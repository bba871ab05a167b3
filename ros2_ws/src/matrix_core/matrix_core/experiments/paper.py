"""The MATRIX paper's numbers that our experiments are compared with (percent), exactly as the
paper states them. A :class:`Figure` keeps the paper's qualifier: ``~`` where the
paper gives an approximate value (read off a figure or written "about"), ``>`` where it gives a bound.
Statements without a figure are kept as text (``*_NOTE``)."""

from dataclasses import dataclass, field

SOURCE = 'MATRIX paper (its figures as the paper states them)'


@dataclass(frozen=True)
class Figure:
    """One paper figure: ``value`` in percent; ``mark`` is '' (exact), '~' (approximate) or '>' (bound);
    ``decimals``: as the paper prints it (95.0 stays 95.0; None: shortest form)."""

    value: float
    mark: str = ''
    decimals: int = field(default=None, compare=False)

    def __post_init__(self):
        if self.mark not in ('', '~', '>'):
            raise ValueError(f'unknown mark {self.mark!r}')

    def __str__(self) -> str:
        number = f'{self.value:g}' if self.decimals is None else f'{self.value:.{self.decimals}f}'
        return f'{self.mark}{number}'


def _f(text: str) -> Figure:
    """'~89' -> Figure(89, '~'); '>80' -> Figure(80, '>'); '5.72' -> Figure(5.72)."""
    mark = text[0] if text[0] in '~>' else ''
    number = text[len(mark) :]
    return Figure(float(number), mark, len(number.split('.')[1]) if '.' in number else 0)


def _row(text: str) -> dict:
    """'94.1 / 81.3 / - / -' -> {'MODA': 94.1, 'MODP': 81.3} (MODA / MODP / MOTA / MOTP; '-' = not given)."""
    values = [v.strip() for v in text.split('/')]
    return {k: _f(v) for k, v in zip(('MODA', 'MODP', 'MOTA', 'MOTP'), values) if v != '-'}


# Table III, "Stationary Dataset Performance": method -> dataset -> metric -> Figure (all exact).
STATIONARY_DATASETS = ('Wildtrack', 'MultiviewX')
STATIONARY = {
    'MVTT': (_row('94.1 / 81.3 / - / -'), _row('95.0 / 92.8 / - / -')),
    'MVDet': (_row('88.2 / 75.7 / - / -'), _row('83.9 / 79.6 / - / -')),
    'MVDeTr': (_row('91.5 / 82.1 / - / -'), _row('93.7 / 91.3 / - / -')),
    'EarlyBird': (_row('91.2 / 81.8 / 89.5 / 86.6'), _row('94.2 / 90.1 / 88.4 / 86.2')),
    'TrackTacular': (_row('91.8 / 79.8 / 89.6 / 81.7'), _row('95.9 / 89.2 / 91.4 / 86.7')),
    'REMP': (_row('90.9 / 79.4 / 88.5 / 86.8'), _row('89.9 / 90.5 / 81.0 / 85.8')),
    'proposed': (_row('91.2 / 79.7 / 89.7 / 81.2'), _row('93.0 / 90.3 / 90.7 / 86.7')),
}
STATIONARY = {method: dict(zip(STATIONARY_DATASETS, rows)) for method, rows in STATIONARY.items()}

# Moving drones, per variant: method -> metric -> Figure (metric names as in records.METRICS).
SIMPLE = {
    'EarlyBird': {'MODA': _f('94'), 'recall': _f('95.9')},
    'TrackTacular': {'MOTA': _f('92.7'), 'IDF1': _f('79.64')},
}
SIMPLE_PROPOSED_NOTE = 'the proposed method: "marginally lower" (no figure)'
COMPLEX = {
    'TrackTacular': {'MODA': _f('5.72'), 'MOTA': _f('31.44'), 'MT': _f('0')},
    'proposed': {'MODA': _f('~89'), 'MOTA': _f('~88.5'), 'precision': _f('~97'), 'recall': _f('~86'), 'MT': _f('~80')},
}
VARIANTS = {'simple': SIMPLE, 'complex': COMPLEX}

# Transfer to the modified variant trained on TRANSFER_SHARE of its data: from scratch vs pretrained on complex.
TRANSFER_SHARE = 0.5
TRANSFER = {'scratch': {'MODA': _f('~54'), 'MODP': _f('>80')}, 'pretrained': {'MODA': _f('~69'), 'MODP': _f('>80')}}
TRANSFER_NOTE = 'MOTA and MOTP "relatively similar" for both'

# Camera dropout: (variant, metric) -> {drop rate: Figure}.
DROPOUT = {
    ('simple', 'MODA'): {0.25: _f('>80'), 0.75: _f('~45')},
    ('complex', 'MODA'): {0.25: _f('>80'), 0.75: _f('~36')},
    ('complex', 'MOTA'): {0.25: _f('>80'), 0.75: _f('~40')},
    ('simple', 'MOTA'): {0.75: _f('~60')},
}
DROPOUT_MOTA_NOTE = 'complex MOTA > 80 up to 0.25'
DROPOUT_MODP_NOTE = 'MODP "relatively stable"'
DROPOUT_MOTP_RANGE = (75.0, 85.0)  # MOTP within 75-85 for all rates (both variants)

# Training and statistics.
EPOCHS = 100
RUNS = 10
RUNS_VARY = 'the RANSAC of registration'  # mean and standard deviation over RUNS runs
BASELINES_NOTE = 'baselines deterministic'
