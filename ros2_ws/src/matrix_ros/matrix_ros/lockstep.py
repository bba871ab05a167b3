"""The bag player's lockstep: which published frames the graph has processed, and the wait for them.

A frame is *released* once ``count`` messages stamped with its time arrived on the lockstep topic (the
monitor's ``frame_done``, or fuse's tracks). At most ``window`` frames are out (published, not released):
with 1 the next frame leaves only after the last one is released; with 2 it leaves while the last is
finished, so the drones register frame k + 1 while fuse fuses frame k (every node still gets every frame,
in order, and waits for all of it: the results do not depend on the machine's speed).
"""

from typing import Callable

from matrix_core.message_fields import stamp_seconds


class LockstepWindow:
    """Args:
    window: frames out at most; count: lockstep messages that release a frame;
    timeout: seconds to wait for one frame's release before going on (the frame then counts as timed out);
    spin_for: ``spin_for(seconds, until)`` spins the node until ``until()`` or the time is up;
    warn: logs a warning line.
    """

    def __init__(self, window: int, count: int, timeout: float, spin_for: Callable, warn: Callable[[str], None]):
        if window < 1 or count < 1 or timeout <= 0:
            raise ValueError(f'lockstep needs window >= 1, count >= 1, timeout > 0 (got {window}, {count}, {timeout})')
        self.window, self.count, self.timeout, self.spin_for, self.warn = window, count, timeout, spin_for, warn
        self.released = {}  # stamp (s) -> lockstep messages seen
        self.out = []  # stamps published and not released yet, oldest first
        self.timed_out = []  # stamps whose release never came

    def on_message(self, msg) -> None:
        """A message on the lockstep topic: a std_msgs/Header or any stamped message."""
        header = msg if hasattr(msg, 'frame_id') else msg.header
        stamp = self.key(stamp_seconds(header.stamp))
        self.released[stamp] = self.released.get(stamp, 0) + 1

    @staticmethod
    def key(seconds: float) -> float:
        return round(seconds, 6)

    def sent(self, seconds: float, describe: str) -> None:
        """Frame ``seconds`` (its stamp) was published; wait while ``window`` frames are out.
        ``describe`` names it in the warning, e.g. 'frame 3 (t=1.500 s)'."""
        self.out.append((self.key(seconds), describe))
        while len(self.out) >= self.window:
            self._await(*self.out.pop(0))

    def finish(self) -> None:
        """Wait for every frame still out (the player's last ones)."""
        while self.out:
            self._await(*self.out.pop(0))

    def _await(self, stamp: float, describe: str) -> None:
        self.spin_for(self.timeout, lambda: self.released.get(stamp, 0) >= self.count)
        if self.released.get(stamp, 0) < self.count:
            self.timed_out.append(stamp)
            self.warn(
                f'lockstep: only {self.released.get(stamp, 0)}/{self.count} messages for {describe} after '
                f'{self.timeout} s; going on'
            )
