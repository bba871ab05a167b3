"""Time going back: telling a replay that started over from messages that are merely late. The one detector
of it (:class:`StampRestart`) and its one setting (:class:`RestartSettings`), for every component that keeps
state across frames: calib and register per drone, fuse for the whole graph.

A stream's stamps normally grow; an item a little older than the newest is late (the synchroniser refuses
it). Stamps that go back by more than ``restart_gap_s`` mean the sequence started over: a bag replayed again
under ``use_sim_time``, a clock reset. The component then starts afresh (its synchroniser, its per-drone or
tracking state) instead of refusing every message of the new run as late or comparing it with the old run's
last frame.
"""

from dataclasses import dataclass, field

from matrix_core.settings import Settings

RESTART_GAP_S = 2.0  # seconds back that mean a new run: several frame periods, more than any message is late


@dataclass
class RestartSettings(Settings):
    """When the stamps go back far enough to start afresh (calib, register, fuse: one name, one default)."""

    restart_gap_s: float = field(
        default=RESTART_GAP_S,
        metadata={
            'help': 'stamps going back by more than this many seconds (a replay started over, e.g. under '
            'use_sim_time) start afresh: calib and register that drone (its first prior or reference again), '
            'fuse its synchroniser, tracks and temporal features; no message of the new run refused as late'
        },
    )

    def check(self) -> None:
        check_restart_gap(self.restart_gap_s)


def check_restart_gap(gap_s: float) -> None:
    if not gap_s > 0:
        raise ValueError(f'restart_gap_s must be positive, got {gap_s}')


class StampRestart:
    """Whether a stamp (seconds) lies more than ``gap_s`` before the newest stamp taken in so far.

    ``went_back(stamp)`` checks a stamp and takes it in (a stream whose every stamp counts: a drone's images);
    ``is_back(stamp)`` only checks and ``note(stamp)`` takes in, for a component that compares what arrives
    with what it has processed (fuse: with the last fused frame, so that a drone lagging behind the others is
    late, not a new run). After going back, the newest is the new run's stamp."""

    def __init__(self, gap_s: float = RESTART_GAP_S):
        check_restart_gap(gap_s)
        self.gap_s, self.newest = gap_s, None

    def is_back(self, stamp: float) -> bool:
        return self.newest is not None and stamp < self.newest - self.gap_s

    def note(self, stamp: float) -> None:
        self.newest = stamp if self.newest is None else max(self.newest, stamp)

    def forget(self) -> None:
        """Start afresh: no stamp taken in."""
        self.newest = None

    def went_back(self, stamp: float) -> bool:
        back = self.is_back(stamp)
        if back:
            self.forget()
        self.note(stamp)
        return back
