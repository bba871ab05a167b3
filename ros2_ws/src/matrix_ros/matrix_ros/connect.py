"""Subscribe a node's frame stream only once the streams that complete each frame are connected.

Why: a reliable, volatile subscription gets only what is published after its publisher has matched it,
and matching between two processes can take seconds on a loaded machine. A fuse node that already
receives a drone's images while that drone's homography publisher has not matched it yet loses the
frame's homography for good (a lockstep replay then waits for that frame until it times out). When the
images are subscribed only after the homography stream has a matched publisher, whoever waits for the
image subscription (the player's ``wait_for_subscribers``) also waits for the homography connection.
Images without their geometry are of no use to these nodes, so nothing is lost by subscribing later.
This closes only one side: discovery runs each way separately, so the subscription may see its publisher
while that publisher does not see the subscription yet, and what it publishes meanwhile still misses it. A
subscriber that cannot lose a message also asks for transient-local history (fuse: ``geometry_qos``), which
the workspace's publishers offer (``matrix_ros.qos``). The same one-sided window exists between a player
and the image subscriptions it waits for: it counts a subscription as soon as its own writer matched it, while
the subscriber may not have matched the writer yet and would drop the first frame (seen in simulated lockstep
runs of ``bench_graph.py``: frame 0 of one drone never reached fuse). A player therefore
starts only once the subscriptions have been there for ``SETTLE_S`` (:class:`SubscribersReady`).
"""

from typing import Callable

from rclpy.clock import Clock, ClockType

# Seconds every awaited subscription must stay matched before a player starts: time for the subscriber to
# match the player's writer too (both directions of discovery usually complete within milliseconds here).
SETTLE_S = 1.0


class SubscribeWhenConnected:
    """Calls ``subscribe()`` once every subscription in ``needs`` has at least one matched publisher.

    ``name`` labels the log lines (e.g. the view). The check runs on a steady-clock timer every ``period_s``
    (sim time may stand still while a player waits); the timer is destroyed once ``subscribe`` ran.
    """

    def __init__(self, node, name: str, needs: list, subscribe: Callable[[], None], period_s: float = 0.1):
        self.node, self.name, self.needs, self.subscribe = node, name, list(needs), subscribe
        self.connected, self.announced = False, False
        self.timer = node.create_timer(period_s, self._check, clock=Clock(clock_type=ClockType.STEADY_TIME))
        self._check()

    def _check(self) -> None:
        if self.connected:
            return
        waiting = [s.topic_name for s in self.needs if s.get_publisher_count() < 1]
        if waiting:
            if not self.announced:
                self.announced = True
                self.node.get_logger().info(
                    f'{self.name}: waiting for a publisher on {", ".join(waiting)} before subscribing its images'
                )
            return
        self.connected = True
        self.subscribe()
        if self.timer is not None:
            self.node.destroy_timer(self.timer)
            self.timer = None
        self.node.get_logger().info(
            f'{self.name}: {", ".join(s.topic_name for s in self.needs)} connected; images subscribed'
        )


class SubscribersReady:
    """Whether every publisher in ``pubs`` (topic -> publisher) has had ``need`` matched subscriptions for
    ``settle_s`` seconds without a break (``ready(now)``, ``now`` on a steady clock, seconds); always
    ready when ``need`` is 0 (nothing awaited)."""

    def __init__(self, pubs: dict, need: int, settle_s: float = SETTLE_S):
        self.pubs, self.need, self.settle_s, self.since = pubs, need, settle_s, None

    def short(self) -> dict:
        """topic -> its subscription count, of the topics with fewer than ``need``."""
        counts = {t: p.get_subscription_count() for t, p in self.pubs.items()}
        return {t: n for t, n in counts.items() if n < self.need}

    def ready(self, now: float) -> bool:
        if self.need <= 0:
            return True
        if self.short():
            self.since = None
            return False
        self.since = now if self.since is None else self.since
        return now - self.since >= self.settle_s
