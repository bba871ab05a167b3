"""Which of a drone's frames cross its link: a frame leaves only once the link has had time to carry the ones
before it; the others are dropped whole, at the sender.

A link slower than the camera cannot carry every frame. Queued (in a radio modem's buffer, in DDS's
history), frames fall further and further behind; sent anyway, the link's queue overflows and drops
packets, and a frame that loses one packet is lost whole after using its share of the link (measured:
at 4 Mbit/s for 6 Mbit/s of images, 1 frame in 30 reached the ground). The gate keeps a budget
of ``link_mbit``: a frame of n bytes occupies the link for ``n * WIRE_OVERHEAD * 8 / link_mbit``
microseconds from when it leaves, and a frame offered before the link is free is dropped before it costs
the link anything. So at most one frame is in flight, whole frames cross, and the latency a frame adds is
its own transfer time. ``link_mbit`` 0: no budget, every frame leaves (a link known to be fast enough).

Why not pace on the ground's DDS acknowledgements of each frame (no rate to set)? On a
link slower than the writer's heartbeat (0.1 s here) the reader asks again for the fragments still queued
in the link, the writer resends them, and the duplicates overflow the link's queue (measured: 1468 packets
dropped in one 45-frame run at 4 Mbit/s).
"""

from dataclasses import dataclass

SENT, DROPPED = 'sent', 'dropped'  # LinkGate.offer's outcomes
# Bytes on the link per byte of image: Ethernet, IP and UDP headers of each ~1.5 kB packet, RTPS headers of
# each fragment (a 745 kB JPEG: about 540 packets, 24 kB of headers)
WIRE_OVERHEAD = 1.035


@dataclass
class LinkCounts:
    """Frames offered so far, by outcome, and the bytes sent."""

    sent: int = 0
    dropped: int = 0  # dropped at the sender: the link was still carrying the frames before
    sent_bytes: int = 0


class LinkGate:
    """One drone's link: :meth:`offer` each frame as it comes from the camera.

    Args:
        link_mbit: the link rate the frames may use (Mbit/s, >= 0; 0: every frame leaves). Leave room for the
            link's other streams (geometry and diagnostics: ~2 kB a frame) and DDS discovery.
    """

    def __init__(self, link_mbit: float):
        if not link_mbit >= 0:
            raise ValueError(f'link_mbit must be >= 0 (0: no budget), got {link_mbit}')
        self.link_mbit = link_mbit
        self.counts = LinkCounts()
        self._free_at = float('-inf')  # monotonic seconds the link has carried every frame sent

    def transfer_s(self, n_bytes: int) -> float:
        """Seconds a frame of ``n_bytes`` occupies the link (0 without a budget)."""
        return n_bytes * WIRE_OVERHEAD * 8 / (self.link_mbit * 1e6) if self.link_mbit else 0.0

    def busy_s(self, now: float) -> float:
        """Seconds from ``now`` until the link has carried every frame sent (0: free)."""
        return max(0.0, self._free_at - now)

    def offer(self, now: float, n_bytes: int) -> str:
        """What happens to the frame of ``n_bytes`` offered at ``now`` (monotonic seconds): ``SENT`` or
        ``DROPPED``."""
        if self.busy_s(now) > 0:
            self.counts.dropped += 1
            return DROPPED
        self._free_at = now + self.transfer_s(n_bytes)
        self.counts.sent += 1
        self.counts.sent_bytes += n_bytes
        return SENT
