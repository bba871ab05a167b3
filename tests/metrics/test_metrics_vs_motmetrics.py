"""Our metrics against py-motmetrics on the same noisy, switching, fragmented tracks (to 1e-6)."""

import motmetrics as mm
import numpy as np
import pytest

from matrix_core.metrics import BevPoints, detection_metrics, tracking_metrics


def simulated_sequence(seed: int, people: int = 12, frames: int = 40):
    """Random walkers as ground truth and a deliberately flawed tracker output (noise, drops, swaps,
    false alarms, re-born ids, frames without any output)."""
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 12, (people, 2))
    vel = rng.normal(0, 0.5, (people, 2))
    gt, pred = [], []
    track_of = np.arange(people) + 100
    next_id = 1000
    for f in range(frames):
        vel += rng.normal(0, 0.15, vel.shape)
        pos += vel * 0.5
        present = rng.random(people) > 0.08
        if f % 13 == 5:  # swap two identities
            a, b = rng.choice(people, 2, replace=False)
            track_of[[a, b]] = track_of[[b, a]]
        if rng.random() < 0.1:  # a track restarts with a fresh id
            track_of[rng.integers(people)] = next_id
            next_id += 1
        for i in np.flatnonzero(present):
            gt.append((f, i, *pos[i]))
            if f % 11 == 7 or rng.random() < 0.12:  # whole frame without output / a miss
                continue
            noise = rng.normal(0, 0.35, 2)
            pred.append((f, track_of[i], *(pos[i] + noise)))
        for _ in range(rng.poisson(0.8)):  # short-lived false tracks
            pred.append((f, next_id, *rng.uniform(0, 12, 2)))
            next_id += 1
    gt, pred = np.array(gt), np.array(pred)
    return (BevPoints(gt[:, 0], gt[:, 2:4], ids=gt[:, 1]), BevPoints(pred[:, 0], pred[:, 2:4], ids=pred[:, 1]))


def motmetrics_summary(gt: BevPoints, pred: BevPoints, gate: float, fresh_ids: bool = False):
    acc = mm.MOTAccumulator(auto_id=False)
    for f in sorted(set(gt.frames) | set(pred.frames)):
        g, p = gt.at(f), pred.at(f)
        d = np.sqrt(mm.distances.norm2squared_matrix(gt.xy[g], pred.xy[p], max_d2=gate**2))
        oids = [(f, k) for k in range(len(g))] if fresh_ids else gt.ids[g]
        hids = [(f, k) for k in range(len(p))] if fresh_ids else pred.ids[p]
        if fresh_ids:  # ids unique per frame: each frame matched on its own (= detection metrics)
            oids = [hash(o) % (2**31) for o in oids]
            hids = [hash(h) % (2**31) + 2**31 for h in hids]
        acc.update(oids, hids, d, frameid=int(f))
    mh = mm.metrics.create()
    return mh.compute(
        acc,
        metrics=[
            'mota',
            'motp',
            'idf1',
            'idp',
            'idr',
            'precision',
            'recall',
            'mostly_tracked',
            'partially_tracked',
            'mostly_lost',
            'num_switches',
            'num_fragmentations',
            'num_false_positives',
            'num_misses',
            'num_unique_objects',
            'num_matches',
        ],
        name='x',
    ).iloc[0]


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_tracking_metrics_match_motmetrics(seed):
    gt, pred = simulated_sequence(seed)
    ours = tracking_metrics(gt, pred, gate=1.0)
    ref = motmetrics_summary(gt, pred, gate=1.0)
    assert ref['num_switches'] > 0 and ref['num_fragmentations'] > 0 and ref['num_false_positives'] > 0
    for mine, theirs in [
        ('mota', 'mota'),
        ('motp_m', 'motp'),
        ('idf1', 'idf1'),
        ('idp', 'idp'),
        ('idr', 'idr'),
        ('precision', 'precision'),
        ('recall', 'recall'),
        ('mostly_tracked', 'mostly_tracked'),
        ('partially_tracked', 'partially_tracked'),
        ('mostly_lost', 'mostly_lost'),
        ('id_switches', 'num_switches'),
        ('fragmentations', 'num_fragmentations'),
        ('fp', 'num_false_positives'),
        ('fn', 'num_misses'),
        ('num_gt_ids', 'num_unique_objects'),
        ('matches', 'num_matches'),
    ]:
        assert getattr(ours, mine) == pytest.approx(float(ref[theirs]), abs=1e-6), mine
    assert ours.motp_percent == pytest.approx(100 * (1 - float(ref['motp'])), abs=1e-6)


@pytest.mark.parametrize('seed', [3, 4])
def test_detection_metrics_match_per_frame_motmetrics(seed):
    gt, pred = simulated_sequence(seed)
    ours = detection_metrics(gt, pred, threshold=0.5)
    ref = motmetrics_summary(gt, pred, gate=0.5, fresh_ids=True)
    assert ref['num_switches'] == 0
    assert ours.moda == pytest.approx(float(ref['mota']), abs=1e-6)
    assert ours.mean_error_m == pytest.approx(float(ref['motp']), abs=1e-6)
    assert ours.modp == pytest.approx(1 - float(ref['motp']) / 0.5, abs=1e-6)
    assert ours.precision == pytest.approx(float(ref['precision']), abs=1e-6)
    assert ours.recall == pytest.approx(float(ref['recall']), abs=1e-6)
    assert (ours.fp, ours.fn) == (int(ref['num_false_positives']), int(ref['num_misses']))
