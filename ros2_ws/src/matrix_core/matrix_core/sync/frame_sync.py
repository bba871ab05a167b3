"""Exact-stamp synchroniser with a timeout, so a stopped stream never stalls the graph.

Convention: stamps and clocks are seconds (floats). ``now`` is whatever clock the caller uses
(ROS time, which follows ``/clock`` under ``use_sim_time``); only differences of ``now`` matter.
"""

from dataclasses import dataclass, field


@dataclass
class FrameSyncSettings:
    streams: list[str] = field(
        default_factory=list,
        metadata={'help': 'names of the streams a complete frame needs (e.g. D1/image, D1/homography)'},
    )
    timeout: float = field(
        default=1.0, metadata={'help': 'seconds to wait for missing streams after the first item of a frame arrived'}
    )
    stamp_tolerance: float = field(
        default=0.001, metadata={'help': 'stamps closer than this (seconds) belong to the same frame'}
    )
    max_pending: int = field(default=16, metadata={'help': 'frames kept waiting at most; the oldest is emitted first'})

    def __post_init__(self):
        if len(set(self.streams)) != len(self.streams):
            raise ValueError(f'duplicate stream names in {self.streams}')
        if self.timeout < 0 or self.stamp_tolerance < 0 or self.max_pending < 1:
            raise ValueError('timeout and stamp_tolerance must be >= 0, max_pending >= 1')


@dataclass
class SyncedFrame:
    """One frame: the items that arrived, by stream, and why it was emitted.

    Attributes:
        stamp: header stamp, seconds.
        items: stream name -> item.
        missing: required streams that did not arrive (sorted).
        reason: 'complete', 'timeout' (waited ``timeout``), 'superseded' (a newer frame completed first),
            'overflow' (more than ``max_pending`` frames waiting) or 'restart' (a new sequence began:
            :meth:`FrameSynchronizer.restart`).
        first_arrival: ``now`` when its first item arrived (the caller's clock): how long the frame waited.
    """

    stamp: float
    items: dict
    missing: list
    reason: str
    first_arrival: float


@dataclass
class _Pending:
    stamp: float
    first_arrival: float
    items: dict = field(default_factory=dict)


class FrameSynchronizer:
    """Collects items per (stream, stamp) and emits frames in stamp order.

    A frame is emitted when all required streams arrived, when ``timeout`` passed since its first item,
    when a newer frame completes (older frames cannot complete any more in an ordered replay), or when
    too many frames are pending. An item older than the last emitted frame is refused and counted in
    ``late_items`` (the caller logs it); nothing is dropped silently. When the caller's
    :class:`~matrix_core.sync.stamp_restart.StampRestart` says time went back, :meth:`restart` emits what was
    pending and takes the next items as a new sequence (``restarts`` counts them).
    """

    def __init__(self, settings: FrameSyncSettings):
        if not settings.streams:
            raise ValueError('FrameSynchronizer needs at least one stream')
        self.settings = settings
        self._pending = []  # sorted by stamp
        self._last_emitted = None
        self.late_items = 0
        self.restarts = 0

    def _find(self, stamp: float):
        for pending in self._pending:
            if abs(pending.stamp - stamp) <= self.settings.stamp_tolerance:
                return pending
        return None

    def add(self, stream: str, stamp: float, item, now: float) -> list:
        """Add one item; returns the frames this completes (possibly empty), oldest first.

        Raises:
            KeyError: ``stream`` is not one of the configured streams.
        """
        if stream not in self.settings.streams:
            raise KeyError(f'unknown stream {stream!r}; configured: {self.settings.streams}')
        out = []
        if self._last_emitted is not None and stamp <= self._last_emitted + self.settings.stamp_tolerance:
            self.late_items += 1
            return out
        pending = self._find(stamp)
        if pending is None:
            pending = _Pending(stamp, now)
            self._pending.append(pending)
            self._pending.sort(key=lambda p: p.stamp)
        pending.items[stream] = item
        if len(pending.items) == len(self.settings.streams):
            while self._pending and self._pending[0] is not pending:
                out.append(self._emit(self._pending[0], 'superseded'))
            out.append(self._emit(pending, 'complete'))
        while len(self._pending) > self.settings.max_pending:
            out.append(self._emit(self._pending[0], 'overflow'))
        return out

    def restart(self) -> list:
        """A new sequence begins (time went back): the frames still pending, oldest first (reason 'restart');
        the next items are refused as late only against the new sequence's frames."""
        out = [self._emit(self._pending[0], 'restart') for _ in range(len(self._pending))]
        self._last_emitted, self.restarts = None, self.restarts + 1
        return out

    def poll(self, now: float) -> list:
        """Frames whose timeout has expired at ``now``, oldest first (call it from a timer)."""
        out = []
        while self._pending and now - self._pending[0].first_arrival >= self.settings.timeout:
            out.append(self._emit(self._pending[0], 'timeout'))
        return out

    def flush(self) -> list:
        """Emit everything still pending (end of a sequence)."""
        out = []
        while self._pending:
            out.append(self._emit(self._pending[0], 'timeout'))
        return out

    @property
    def pending_stamps(self) -> list:
        return [p.stamp for p in self._pending]

    def waiting_before(self, stamp: float) -> bool:
        """Whether a frame earlier than ``stamp`` (by more than the stamp tolerance) is still pending."""
        return any(p.stamp < stamp - self.settings.stamp_tolerance for p in self._pending)

    def _emit(self, pending: _Pending, reason: str) -> SyncedFrame:
        self._pending.remove(pending)
        self._last_emitted = pending.stamp
        missing = sorted(set(self.settings.streams) - set(pending.items))
        return SyncedFrame(pending.stamp, dict(pending.items), missing, reason, pending.first_arrival)
