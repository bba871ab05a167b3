"""ByteTrack-style tracker of people on the ground plane (Kalman constant velocity, Hungarian, metre gate)."""

from matrix_core.tracking.settings import TrackerSettings
from matrix_core.tracking.track import BevDetections
from matrix_core.tracking.tracker import BevTracker, TrackOutput

__all__ = ['TrackerSettings', 'BevDetections', 'BevTracker', 'TrackOutput']
