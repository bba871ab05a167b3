"""A per-drone node's answer to a replay that started over (``matrix_core.sync.stamp_restart``)."""

from matrix_core.sync import StampRestart
from matrix_core.message_fields import stamp_seconds


class DroneRestarts:
    """``check(view, header)``, before a drone's message is handled: when the drone's stamps went back by more
    than ``gap_s``, log it and call ``start(view)``, which starts that drone afresh."""

    def __init__(self, node, gap_s: float, start):
        self.node, self.gap_s, self.start, self.streams = node, gap_s, start, {}

    def check(self, view: str, header) -> None:
        stamp = stamp_seconds(header.stamp)
        if self.streams.setdefault(view, StampRestart(self.gap_s)).went_back(stamp):
            self.node.get_logger().warning(f'{view}: t={stamp:.3f} s: time went back, starting this drone afresh')
            self.start(view)

    def checked(self, view: str, handler):
        """A subscription callback: :meth:`check`, then ``handler(msg)``."""

        def callback(msg):
            self.check(view, msg.header)
            handler(msg)

        return callback
