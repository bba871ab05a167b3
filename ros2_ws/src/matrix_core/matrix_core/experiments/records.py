"""Reading a run's results back: the ``metrics.json`` of every evaluation and ``run.json``, and the small
aggregations the report needs (percent values, mean and standard deviation over seeds)."""

import json
import math
from pathlib import Path

import numpy as np


def _hota(field: str):
    """Reads ``hota[field]`` in percent; None for a record written before evaluations reported HOTA."""
    return lambda r: 100 * r['hota'][field] if r.get('hota') else None


# Metric name -> how to read it (in percent) from a metrics.json record.
METRICS = {
    'MODA': lambda r: 100 * r['detection']['moda'],
    'MODP': lambda r: 100 * r['detection']['modp'],
    'precision': lambda r: 100 * r['detection']['precision'],
    'recall': lambda r: 100 * r['detection']['recall'],
    'MOTA': lambda r: 100 * r['tracking']['mota'],
    'MOTP': lambda r: r['tracking']['motp_percent'],
    'IDF1': lambda r: 100 * r['tracking']['idf1'],
    'MT': lambda r: 100 * r['tracking']['mostly_tracked'] / max(r['tracking']['num_gt_ids'], 1),
    'ML': lambda r: 100 * r['tracking']['mostly_lost'] / max(r['tracking']['num_gt_ids'], 1),
    'HOTA': _hota('hota'),
    'DetA': _hota('det_a'),
    'AssA': _hota('ass_a'),
}


def load_records(run_dir) -> list:
    """Every ``eval/*/metrics.json`` of a run, sorted by step folder name."""
    return [json.loads(p.read_text()) for p in sorted(Path(run_dir).glob('eval/*/metrics.json'))]


def load_table(run_dir, name: str):
    """The ``metrics.json`` of a non-evaluation step (e.g. ``tables/multiviewx_sample``), or None."""
    path = Path(run_dir) / name / 'metrics.json'
    return json.loads(path.read_text()) if path.is_file() else None


def load_done(run_dir) -> dict:
    """Every ``steps/<name>.done.json`` of a run: step name -> record (kind, params, wall_s, commit)."""
    steps = Path(run_dir) / 'steps'
    return {
        str(p.relative_to(steps))[: -len('.done.json')]: json.loads(p.read_text())
        for p in sorted(steps.glob('**/*.done.json'))
    }


def load_run(run_dir) -> dict:
    path = Path(run_dir) / 'run.json'
    if not path.is_file():
        raise FileNotFoundError(f'{path} is missing: run `matrix-tracker experiments` first')
    return json.loads(path.read_text())


def select(records: list, **criteria) -> list:
    """Records whose fields equal every criterion (``dropped=[]`` selects runs with all views)."""
    return [r for r in records if all(r.get(k) == v for k, v in criteria.items())]


def one(records: list, **criteria):
    """The single full-view record matching ``criteria`` (by default not a plain-RANSAC registration run
    of the run-to-run experiment: ``ransac_seed=None``), or None."""
    found = select(records, **{'dropped': [], 'ransac_seed': None, **criteria})
    return found[0] if found else None


def value(record, metric: str) -> float:
    """``metric`` of ``record`` in percent; nan when the record is missing or the metric undefined."""
    if record is None:
        return math.nan
    v = METRICS[metric](record)
    return math.nan if v is None else float(v)


def mean_std(values) -> tuple:
    """(mean, sample standard deviation) ignoring nan; std is nan for fewer than two values."""
    v = np.asarray([x for x in values if not math.isnan(x)], float)
    if not len(v):
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if len(v) > 1 else math.nan
