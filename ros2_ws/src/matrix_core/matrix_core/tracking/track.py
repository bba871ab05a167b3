"""One tracked person and the detections the tracker consumes."""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BevDetections:
    """Detections of one frame on the ground plane.

    Attributes:
        xy: (N, 2) world metres.
        scores: (N,) confidences in [0, 1].
        offsets: (N, 2) metres from each detection to the same person's position in the PREVIOUS frame
            (CenterTrack tracking offset), or None when the detector has none.
    """

    xy: np.ndarray
    scores: np.ndarray
    offsets: np.ndarray = None

    def __post_init__(self):
        xy = np.asarray(self.xy, dtype=np.float64).reshape(-1, 2)
        scores = np.asarray(self.scores, dtype=np.float64).reshape(-1)
        if len(scores) != len(xy):
            raise ValueError(f'{len(xy)} positions but {len(scores)} scores')
        offsets = None if self.offsets is None else np.asarray(self.offsets, dtype=np.float64).reshape(-1, 2)
        if offsets is not None and len(offsets) != len(xy):
            raise ValueError(f'{len(xy)} positions but {len(offsets)} offsets')
        for name, arr in (('xy', xy), ('scores', scores), ('offsets', offsets)):
            if arr is not None and not np.all(np.isfinite(arr)):
                raise ValueError(f'detections: {name} contains NaN or infinite values')
        object.__setattr__(self, 'xy', xy)
        object.__setattr__(self, 'scores', scores)
        object.__setattr__(self, 'offsets', offsets)

    def __len__(self) -> int:
        return len(self.xy)


class Track:
    """Kalman state plus bookkeeping. ``track_id`` is None until the track is confirmed (born)."""

    def __init__(self, mean, cov, score: float):
        self.mean, self.cov = mean, cov
        self.score = score
        self.track_id = None
        self.hits = 1  # matched frames in a row
        self.misses = 0  # unmatched frames in a row
        self.last_xy = mean[:2].copy()  # filtered position at the last match
        self.detection_xy = mean[:2].copy()  # position of the last matched detection

    @property
    def confirmed(self) -> bool:
        return self.track_id is not None

    @property
    def xy(self) -> np.ndarray:
        return self.mean[:2]

    @property
    def velocity(self) -> np.ndarray:
        return self.mean[2:]
