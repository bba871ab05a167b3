"""One plain-text table of detection, tracking and HOTA metrics (what ``score`` and ``evaluate`` print)."""

import math

from matrix_core.metrics.detection import DetectionMetrics
from matrix_core.metrics.hota import HotaMetrics
from matrix_core.metrics.tracking import TrackingMetrics


def _pct(v: float) -> str:
    return '   n/a' if v is None or math.isnan(v) else f'{100 * v:6.2f} %'


def format_metrics(det: DetectionMetrics = None, trk: TrackingMetrics = None, hota: HotaMetrics = None) -> str:
    """Aligned ``name  value`` lines; rates in percent, distances in metres, counts as integers."""
    rows = []
    if det is not None:
        rows += [
            (f'MODA (@{det.threshold:g} m)', _pct(det.moda)),
            ('MODP', _pct(det.modp)),
            ('precision', _pct(det.precision)),
            ('recall', _pct(det.recall)),
            ('mean error of TP', f'{det.mean_error_m:6.3f} m'),
            ('TP / FP / FN', f'{det.tp} / {det.fp} / {det.fn}'),
            ('ground-truth points / frames', f'{det.num_gt} / {det.num_frames}'),
        ]
    if trk is not None:
        rows += [
            (f'MOTA (@{trk.gate:g} m)', _pct(trk.mota)),
            ('MOTP (mean distance)', f'{trk.motp_m:6.3f} m'),
            ('MOTP (TrackTacular %)', f'{trk.motp_percent:6.2f} %'),
            ('IDF1', _pct(trk.idf1)),
            ('IDP / IDR', f'{_pct(trk.idp).strip()} / {_pct(trk.idr).strip()}'),
            (
                'MT / PT / ML',
                f'{trk.mostly_tracked} / {trk.partially_tracked} / {trk.mostly_lost} of {trk.num_gt_ids} ids',
            ),
            (
                'MT / ML (% of ids)',
                f'{_pct(trk.mostly_tracked / max(trk.num_gt_ids, 1)).strip()} / '
                f'{_pct(trk.mostly_lost / max(trk.num_gt_ids, 1)).strip()}',
            ),
            ('ID switches', str(trk.id_switches)),
            ('fragmentations', str(trk.fragmentations)),
            ('FP / FN (tracking)', f'{trk.fp} / {trk.fn}'),
        ]
    if hota is not None:
        rows += [
            (f'HOTA (@{hota.gate:g} m)', _pct(hota.hota)),
            ('DetA / AssA', f'{_pct(hota.det_a).strip()} / {_pct(hota.ass_a).strip()}'),
            ('DetRe / DetPr', f'{_pct(hota.det_re).strip()} / {_pct(hota.det_pr).strip()}'),
            ('AssRe / AssPr', f'{_pct(hota.ass_re).strip()} / {_pct(hota.ass_pr).strip()}'),
            ('LocA', _pct(hota.loc_a)),
        ]
    width = max(len(name) for name, _ in rows) if rows else 0
    return '\n'.join(f'{name:<{width}}  {value}' for name, value in rows)
