"""Our ground-plane HOTA against TrackEval's own HOTA on the real MATRIX sample's 500 frames of trajectories
with a seeded, deliberately flawed tracker output; and a few answers that can be worked out by hand."""

import numpy as np
import pytest
import trackeval  # installed by make setup without its dependencies (scripts/setup.sh)

from matrix_core.datasets import MatrixDataset
from matrix_core.metrics import BevPoints
from matrix_core.metrics.hota import ALPHAS, hota_metrics


def sample_trajectories(root) -> BevPoints:
    """``frame id x y`` of every person in ``matchings/Pedestrians`` (500 frames, 40 people)."""
    dataset = MatrixDataset(root)
    frames, ids, xy = [], [], []
    for f in dataset.trajectory_frames:
        for pid, p in dataset.pedestrian_positions(f).items():
            frames.append(f)
            ids.append(pid)
            xy.append(p[:2])
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def flawed_tracks(gt: BevPoints, seed: int) -> BevPoints:
    """Tracks of ``gt`` with 0.1 m noise, 10 % misses, 2 false positives a frame (short-lived false tracks
    of a few frames), an identity swap between two people every 40 frames and now and then a track that
    restarts under a fresh id."""
    rng = np.random.default_rng(seed)
    people = np.unique(gt.ids)
    track_of = {int(p): 100 + k for k, p in enumerate(people)}
    next_id = 10_000
    false_tracks = []  # [id, xy, frames left]
    frames, ids, xy = [], [], []
    for f, rows in sorted(gt.by_frame().items()):
        if f % 40 == 20:
            a, b = rng.choice(people, 2, replace=False)
            track_of[int(a)], track_of[int(b)] = track_of[int(b)], track_of[int(a)]
        if rng.random() < 0.05:
            track_of[int(rng.choice(people))] = next_id
            next_id += 1
        for i in rows:
            if rng.random() < 0.1:
                continue
            frames.append(f)
            ids.append(track_of[int(gt.ids[i])])
            xy.append(gt.xy[i] + rng.normal(0, 0.1, 2))
        while len(false_tracks) < 2:
            false_tracks.append([next_id, rng.uniform(0, 30, 2), int(rng.integers(1, 6))])
            next_id += 1
        for t in false_tracks:
            frames.append(f)
            ids.append(t[0])
            xy.append(t[1] + rng.normal(0, 0.1, 2))
            t[2] -= 1
        false_tracks = [t for t in false_tracks if t[2] > 0]
    return BevPoints(frames, np.reshape(xy, (-1, 2)), ids=ids)


def trackeval_hota(gt: BevPoints, pred: BevPoints, gate: float) -> dict:
    """TrackEval's ``HOTA().eval_sequence`` on the same points, similarity max(0, 1 - d / gate) computed here
    independently of matrix_core; its per-alpha arrays averaged as TrackEval reports them."""
    gt_ids, gi = np.unique(gt.ids, return_inverse=True)
    pred_ids, pi = np.unique(pred.ids, return_inverse=True)
    steps = sorted(set(gt.frames.tolist()) | set(pred.frames.tolist()))
    data = {'gt_ids': [], 'tracker_ids': [], 'similarity_scores': []}
    for f in steps:
        g, p = gt.frames == f, pred.frames == f
        d = np.linalg.norm(gt.xy[g][:, None, :] - pred.xy[p][None, :, :], axis=2)
        data['gt_ids'].append(gi[g])
        data['tracker_ids'].append(pi[p])
        data['similarity_scores'].append(np.maximum(0.0, 1.0 - d / gate))
    data.update(
        num_timesteps=len(steps),
        num_gt_ids=len(gt_ids),
        num_tracker_ids=len(pred_ids),
        num_gt_dets=len(gt),
        num_tracker_dets=len(pred),
    )
    res = trackeval.metrics.HOTA().eval_sequence(data)
    return {k: float(np.mean(res[k])) for k in ('HOTA', 'DetA', 'AssA', 'DetRe', 'DetPr', 'AssRe', 'AssPr', 'LocA')}


OURS = {
    'HOTA': 'hota',
    'DetA': 'det_a',
    'AssA': 'ass_a',
    'DetRe': 'det_re',
    'DetPr': 'det_pr',
    'AssRe': 'ass_re',
    'AssPr': 'ass_pr',
    'LocA': 'loc_a',
}


@pytest.mark.parametrize('seed, gate', [(0, 1.0), (1, 1.0), (2, 0.5)])
def test_hota_matches_trackeval_on_the_real_sample(matrix_sample, seed, gate):
    gt = sample_trajectories(matrix_sample)
    assert len(np.unique(gt.frames)) == 500 and len(np.unique(gt.ids)) == 40
    pred = flawed_tracks(gt, seed)
    ours = hota_metrics(gt, pred, gate)
    theirs = trackeval_hota(gt, pred, gate)
    for name, field in OURS.items():
        # within 0.1 point (percent); the two compute the same sums, so they agree far closer
        assert 100 * getattr(ours, field) == pytest.approx(100 * theirs[name], abs=0.1), name
    # the flaws show: neither perfect nor degenerate, association hurt by the swaps
    assert 0.3 < ours.ass_a < 0.95 and 0.5 < ours.det_a < 0.95
    assert ours.num_gt == len(gt) and ours.num_pred == len(pred)


def test_perfect_tracks_score_one(matrix_sample):
    gt = sample_trajectories(matrix_sample)
    m = hota_metrics(gt, gt)
    assert (m.hota, m.det_a, m.ass_a, m.loc_a) == (1.0, 1.0, 1.0, 1.0)


def test_hand_worked_answers():
    frames = np.arange(10)
    gt = BevPoints(frames, np.zeros((10, 2)), ids=np.zeros(10))
    # 0.4 m off with a 1 m gate: similarity 0.6, a match at the 12 alphas 0.05 ... 0.60 only
    off = BevPoints(frames, np.tile([0.4, 0.0], (10, 1)), ids=np.full(10, 7))
    m = hota_metrics(gt, off, gate=1.0)
    assert np.sum(ALPHAS <= 0.6 + 1e-9) == 12
    assert m.hota == pytest.approx(12 / 19) and m.det_a == pytest.approx(12 / 19)
    assert m.ass_a == pytest.approx(12 / 19)
    # one id for the first half, another for the second: DetA 1, AssA 0.5 (each match's ids share 5 of 10)
    split = BevPoints(frames, np.zeros((10, 2)), ids=(frames >= 5).astype(int))
    m = hota_metrics(gt, split)
    assert m.det_a == pytest.approx(1.0) and m.ass_a == pytest.approx(0.5)
    assert m.hota == pytest.approx(np.sqrt(0.5)) and m.ass_pr == pytest.approx(1.0) and m.ass_re == 0.5
    # nothing tracked, or everything beyond the gate: 0
    nothing = BevPoints(np.zeros(0), np.zeros((0, 2)), ids=np.zeros(0))
    assert hota_metrics(gt, nothing).hota == 0.0
    assert hota_metrics(gt, BevPoints(frames, np.full((10, 2), 5.0), ids=frames)).hota == 0.0


def test_bad_arguments_are_errors():
    pts = BevPoints([0], [[0.0, 0.0]], ids=[1])
    with pytest.raises(ValueError, match='ids'):
        hota_metrics(pts, BevPoints([0], [[0.0, 0.0]]))
    with pytest.raises(ValueError, match='gate'):
        hota_metrics(pts, pts, gate=0.0)
