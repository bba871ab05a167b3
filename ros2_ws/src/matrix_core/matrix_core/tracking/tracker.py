"""ByteTrack-style multi-person tracker on the ground plane.

Per frame: predict every track (constant velocity), match confident detections to all tracks, then
weak detections to the confirmed tracks left over, start tentative tracks from unmatched confident
detections, give a track an id after ``birth_hits`` matched frames, delete it after ``max_misses``
frames without a match (tracks of the very first frame are confirmed at once with
``confirm_first_frame``). Ids are owned by the tracker instance and restart at 1 after ``reset()``.
"""

from dataclasses import dataclass

import numpy as np

from matrix_core.tracking.association import associate
from matrix_core.tracking.kalman import ConstantVelocityKalman
from matrix_core.tracking.settings import TrackerSettings
from matrix_core.tracking.track import BevDetections, Track


@dataclass(frozen=True)
class TrackOutput:
    """A confirmed track matched in the current frame: id, (2,) filtered position (m), (2,) velocity (m/s);
    ``misses`` > 0 only for a coasting track reported at its prediction (``report_coasting``);
    ``detection_xy`` (2,): the position of the detection matched this frame (the prediction when coasting),
    where the person is now: the filtered ``xy`` lags behind it (image boxes use it)."""

    track_id: int
    xy: np.ndarray
    velocity: np.ndarray
    score: float
    misses: int = 0
    detection_xy: np.ndarray = None


class BevTracker:
    """Turns per-frame :class:`BevDetections` into identities. One instance per sequence (or ``reset()``)."""

    def __init__(self, settings: TrackerSettings = None):
        self.settings = settings or TrackerSettings()
        s = self.settings
        self.kf = ConstantVelocityKalman(s.frame_interval_s, s.accel_noise, s.measurement_noise_m)
        self.reset()

    def reset(self) -> None:
        """Forget all tracks; the next confirmed track gets id 1."""
        self.tracks = []
        self._next_id = 1
        self._first_frame = True

    def update(self, dets: BevDetections) -> list:
        """Advance one frame. Returns the :class:`TrackOutput` of confirmed tracks matched in this frame
        (plus, with ``report_coasting``, confirmed tracks missed for at most that many frames, at their
        predicted position)."""
        s = self.settings
        for tr in self.tracks:
            tr.mean, tr.cov = self.kf.predict(tr.mean, tr.cov)
        high = np.flatnonzero(dets.scores >= s.high_score)
        low = np.flatnonzero((dets.scores >= s.low_score) & (dets.scores < s.high_score))
        gates = (s.gate_m, s.gate_growth_m, s.max_gate_m)
        confirmed = [tr for tr in self.tracks if tr.confirmed]
        tentative = [tr for tr in self.tracks if not tr.confirmed]
        # Stage 1: confident detections with the confirmed tracks, tracked or lost (a lost track found again
        # within its grown gate keeps its id).
        pairs, left_t, left_d = associate(confirmed, dets, high, s.use_offsets, *gates)
        matched = [(confirmed[i], j) for i, j in pairs]
        rest = [confirmed[i] for i in left_t]
        # Stage 2: weak detections only extend confirmed tracks (ByteTrack's recovery of occluded people).
        pairs2, _, _ = associate(rest, dets, low, s.use_offsets, *gates)
        matched += [(rest[i], j) for i, j in pairs2]
        # Stage 3: the confident detections left with the tentative tracks, so that a track started by a
        # false positive never takes a person's detection from that person's track.
        pairs3, _, left_d = associate(tentative, dets, left_d, s.use_offsets, *gates)
        matched += [(tentative[i], j) for i, j in pairs3]

        hit = set()
        for tr, j in matched:
            tr.mean, tr.cov = self.kf.update(tr.mean, tr.cov, dets.xy[j])
            tr.last_xy = tr.mean[:2].copy()
            tr.score = float(dets.scores[j])
            tr.detection_xy = dets.xy[j].copy()
            tr.hits += 1
            tr.misses = 0
            if not tr.confirmed and tr.hits >= s.birth_hits:
                tr.track_id, self._next_id = self._next_id, self._next_id + 1
            hit.add(id(tr))
        survivors = []
        for tr in self.tracks:
            if id(tr) not in hit:
                tr.misses += 1
                tr.hits = 0
                if not tr.confirmed or tr.misses > s.max_misses:
                    continue  # tentative tracks die at their first miss
            survivors.append(tr)
        for j in left_d:
            velocity = None
            if s.use_offsets and dets.offsets is not None:
                velocity = -dets.offsets[j] / s.frame_interval_s
            tr = Track(*self.kf.initiate(dets.xy[j], velocity), float(dets.scores[j]))
            if s.birth_hits <= 1 or (self._first_frame and s.confirm_first_frame):
                tr.track_id, self._next_id = self._next_id, self._next_id + 1
                hit.add(id(tr))
            survivors.append(tr)
        self.tracks = survivors
        self._first_frame = False
        return [
            TrackOutput(
                tr.track_id,
                tr.xy.copy(),
                tr.velocity.copy(),
                tr.score,
                tr.misses,
                (tr.detection_xy if tr.misses == 0 else tr.xy).copy(),
            )
            for tr in self.tracks
            if tr.confirmed and (id(tr) in hit or tr.misses <= s.report_coasting)
        ]
