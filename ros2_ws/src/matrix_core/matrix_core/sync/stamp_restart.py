"""Telling a replay that started over from messages that are merely late.

A stream's stamps normally grow; an item a little older than the newest is late (the synchroniser refuses
it). Stamps that go back by more than ``gap_s`` mean the sequence started over: a bag replayed again under
``use_sim_time``, a clock reset. A node then starts that stream afresh (its synchroniser, its per-drone state)
instead of refusing every message of the new run as late or comparing it with the old run's last frame.
"""

from dataclasses import dataclass, field


@dataclass
class RestartSettings:
    """Components that keep per-drone state across frames (calib, register): when the stamps go back."""

    restart_gap_s: float = field(
        default=2.0,
        metadata={
            'help': "a drone's stamps going back by more than this many seconds (a replay started over, e.g. "
            'under use_sim_time) start that drone afresh: its first prior or reference again, no message '
            'of the new run refused as late'
        },
    )

    def __post_init__(self):
        if not self.restart_gap_s > 0:
            raise ValueError(f'restart_gap_s must be positive, got {self.restart_gap_s}')
        if hasattr(super(), '__post_init__'):
            super().__post_init__()


class StampRestart:
    """``went_back(stamp)``: True when ``stamp`` (seconds) is more than ``gap_s`` before the newest stamp seen
    so far; the newest is then ``stamp`` (the new run's clock)."""

    def __init__(self, gap_s: float):
        if not gap_s > 0:
            raise ValueError(f'gap_s must be positive, got {gap_s}')
        self.gap_s, self.newest = gap_s, None

    def went_back(self, stamp: float) -> bool:
        back = self.newest is not None and stamp < self.newest - self.gap_s
        self.newest = stamp if back or self.newest is None else max(self.newest, stamp)
        return back
