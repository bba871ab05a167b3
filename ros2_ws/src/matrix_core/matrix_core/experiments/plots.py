"""PNG figures of RESULTS.md: grouped bar charts (like the paper's figures) and camera-dropout curves."""

import math
from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    return plt


def bar_chart(path, metrics: list, series: dict, title: str, paper: dict = None) -> Path:
    """Grouped bars: one group per metric, one bar per ``series`` entry (label -> values in percent, nan
    = not measured); ``paper`` (label -> values) is drawn hatched beside ours."""
    plt = _plt()
    all_series = [(label, vals, False) for label, vals in series.items()]
    all_series += [(f'paper: {label}', vals, True) for label, vals in (paper or {}).items()]
    n = max(len(all_series), 1)
    width = 0.8 / n
    x = np.arange(len(metrics))
    fig, ax = plt.subplots(figsize=(max(6.5, 1.4 * len(metrics) + 0.5 * n), 5.0), dpi=110)
    for i, (label, vals, is_paper) in enumerate(all_series):
        vals = np.array([np.nan if v is None else v for v in vals], float)
        pos = x - 0.4 + width * (i + 0.5)
        bars = ax.bar(
            pos,
            np.nan_to_num(vals),
            width,
            label=label,
            hatch='//' if is_paper else None,
            alpha=0.55 if is_paper else 0.9,
            edgecolor='black',
            linewidth=0.5,
        )
        for b, v in zip(bars, vals):
            if is_paper and math.isnan(v):
                continue  # the paper gives no number for this metric
            ax.annotate(
                'n/a' if math.isnan(v) else f'{v:.1f}',
                (b.get_x() + b.get_width() / 2, max(v, 0) if not math.isnan(v) else 0),
                ha='center',
                va='bottom',
                fontsize=7,
            )
    ax.axhline(0, color='black', linewidth=0.8)
    ax.set_xticks(x, metrics)
    ax.set_ylabel('%')
    ax.set_title(title)
    ax.legend(fontsize=7, loc='upper center', bbox_to_anchor=(0.5, -0.08), ncol=3, frameon=False)
    ax.grid(axis='y', alpha=0.3)
    return _save(plt, fig, path)


def _paper_marker(ax, x: float, figure, color, label: str = None) -> None:
    """A paper figure as a star (approximate '~' or exact) or a triangle pointing up (a '>' bound)."""
    ax.plot(
        [x],
        [figure.value],
        marker='^' if figure.mark == '>' else '*',
        markersize=11,
        linestyle='none',
        color=color,
        markeredgecolor='black',
        alpha=0.75,
        label=label,
    )
    ax.annotate(str(figure), (x, figure.value), textcoords='offset points', xytext=(6, 2), fontsize=7)


def dropout_curves(
    path, curves: dict, metrics=('MODA', 'MODP', 'MOTA', 'MOTP'), paper_points: dict = None, bands: dict = None
) -> Path:
    """One panel per metric: value vs drop rate with +-1 std bars. ``curves``: label -> {rate: {metric:
    (mean, std)}}; ``paper_points``: (label, metric) -> {rate: paper.Figure}, drawn as markers in the
    colour of that label's curve; ``bands``: metric -> (low, high), a range the paper states (shaded)."""
    plt = _plt()
    fig, axes = plt.subplots(2, 2, figsize=(9, 7), dpi=110)
    for ax, metric in zip(axes.ravel(), metrics):
        colors = {}
        for label, by_rate in curves.items():
            rates = sorted(by_rate)
            mean = [by_rate[r][metric][0] for r in rates]
            std = [0.0 if math.isnan(by_rate[r][metric][1]) else by_rate[r][metric][1] for r in rates]
            line = ax.errorbar(rates, mean, yerr=std, marker='o', capsize=3, label=label)
            colors[label] = line[0].get_color()
        for (label, m), points in (paper_points or {}).items():
            if m == metric:
                for i, (rate, figure) in enumerate(sorted(points.items())):
                    _paper_marker(ax, rate, figure, colors.get(label, 'black'), f'paper, {label}' if i == 0 else None)
        if metric in (bands or {}):
            low, high = bands[metric]
            ax.axhspan(low, high, color='grey', alpha=0.15, label=f'paper: {low:g}-{high:g}')
        ax.set_title(metric)
        ax.set_xlabel('share of views dropped')
        ax.set_ylabel('%')
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle('Camera dropout at test time (mean +- std over random view subsets; markers: paper)')
    return _save(plt, fig, path)


def share_curves(path, curves: dict, paper_points: dict = None, metric: str = 'MODA') -> Path:
    """``metric`` against the share of training data: ``curves``: label -> {share: value in percent}
    (nan = not measured); ``paper_points``: label -> {share: paper.Figure}, drawn in that curve's colour."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.5, 4.5), dpi=110)
    colors = {}
    for label, by_share in curves.items():
        shares = sorted(by_share)
        (line,) = ax.plot([100 * x for x in shares], [by_share[x] for x in shares], marker='o', label=label)
        colors[label] = line.get_color()
    for label, points in (paper_points or {}).items():
        for i, (share, figure) in enumerate(sorted(points.items())):
            _paper_marker(ax, 100 * share, figure, colors.get(label, 'black'), f'paper, {label}' if i == 0 else None)
    ax.set_xscale('log')
    ax.set_xticks([100 * x for x in sorted({x for c in curves.values() for x in c})] or [50])
    from matplotlib.ticker import FormatStrFormatter, NullFormatter

    ax.xaxis.set_major_formatter(FormatStrFormatter('%g'))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel('share of the modified variant\'s training frames (%)')
    ax.set_ylabel(f'{metric} (%)')
    ax.set_title(f'Transfer: {metric} vs training share, from scratch vs pretrained on complex')
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(plt, fig, path)


def _save(plt, fig, path) -> Path:
    """Lay out, write (creating the folder) and close a figure; returns the path."""
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
    return path
