"""Replays that end by themselves under ``ros2 launch``: the launch-side twin of ``run_graph``'s loop.

Once the player has played the whole bag (and the monitor, if any, has written its scores) every node is
stopped (SIGINT: the recorder closes its bag) and ``ros2 launch`` exits 0. It exits non-zero, saying why,
when the player's lockstep timed out for some frame (player code 3), nothing was played, the monitor could
score nothing, another node died before the end, or some drone was left out at start (``drone_check``; the
replay ran, and its ``replay done:`` line names the drone). ``launch`` has a single failure code (1: an error
raised in an event handler shuts the launch down, stopping every node as a Shutdown event does), so the
reason is in the message, not in the code: where ``run_graph`` exits 4 or 5, the launch exits 1.

Imported only by ``full_graph.launch.py`` (it needs the ``launch`` package; ``graph`` and ``run_graph``
do not).
"""

from launch.actions import EmitEvent, LogInfo, OpaqueFunction, RegisterEventHandler, TimerAction
from launch.event_handlers import OnProcessExit
from launch.events import Shutdown

from matrix_bringup.drone_check import ran_without_text
from matrix_bringup.graph import player_exit_text

# Without a monitor the player exits once the fuse node published the last frame's tracks; the recorder
# gets them at about the same time, this long is left for it (as run_graph does).
SETTLE_S = 1.0


class ReplayFailed(RuntimeError):
    """A replay that did not process every frame: ``ros2 launch`` logs the message and exits 1."""


class ReplayEnd:
    """Event handlers that end the launch after the replay. ``actions``: the launch_ros ``Node`` actions,
    by label ('fuse', 'D3/calib', ...); ``player`` and ``monitor`` (or None) are labels among them;
    ``monitor_timeout_s``: how long the monitor may take to score after the last frame; ``left_out``: the
    drones left out at start, view -> why (``drone_check.without_unreadable_drones``): said again when the
    replay ends, and the launch then fails."""

    def __init__(
        self, actions: dict, player: str, monitor: str = None, monitor_timeout_s: float = 120.0, left_out: dict = None
    ):
        self.actions, self.player, self.monitor, self.left_out = actions, player, monitor, dict(left_out or {})
        self.monitor_timeout_s = monitor_timeout_s
        self.exited = {}  # label -> exit code, of the player and the monitor
        self.ending = False  # once true, processes exit because the launch stops them

    def handlers(self) -> list:
        """One ``OnProcessExit`` per node; put them before the nodes in the launch description."""
        return [
            RegisterEventHandler(OnProcessExit(target_action=action, on_exit=self._on_exit(label)))
            for label, action in self.actions.items()
        ]

    def _on_exit(self, label):
        return lambda event, context: self._exited(label, event.returncode)

    def _exited(self, label: str, code: int):
        if self.ending:
            return None
        if label == self.player:
            if code != 0:
                raise ReplayFailed(f'bag_player exited with code {code}{player_exit_text(code)}')
        elif label == self.monitor:
            if code != 0:
                raise ReplayFailed(f'{label} exited with code {code} (it could score nothing; see its output above)')
        else:
            raise ReplayFailed(f'{label} exited early (code {code}; see its output above)')
        self.exited[label] = code
        if self.player not in self.exited:
            return None
        if self.monitor and self.monitor not in self.exited:  # its scores come after the last frame
            return [
                TimerAction(
                    period=self.monitor_timeout_s,
                    actions=[
                        OpaqueFunction(
                            function=lambda _: self._end(
                                f'{self.monitor} did not finish within {self.monitor_timeout_s:g} s of the last frame'
                            )
                        )
                    ],
                )
            ]
        if self.monitor:
            return self._end('the bag was played and the monitor wrote its scores')
        return [
            TimerAction(
                period=SETTLE_S,
                actions=[OpaqueFunction(function=lambda _: self._end(f'the bag was played{player_exit_text(0)}'))],
            )
        ]

    def _end(self, reason: str) -> list:
        if self.ending:
            return []
        self.ending = True
        if not self.left_out:
            return [
                LogInfo(msg=f'replay done: {reason}; stopping every node'),
                EmitEvent(event=Shutdown(reason=reason)),
            ]
        reason += f'; {ran_without_text(self.left_out)}'
        return [LogInfo(msg=f'replay done: {reason}; stopping every node'), OpaqueFunction(function=self._left_out)]

    def _left_out(self, context):
        """Every frame was played, without some drones: exit 1 (the launch's failure code) naming them."""
        raise ReplayFailed(ran_without_text(self.left_out))
