"""One drone's calib and register nodes in one process (``matrix_bringup.drone``): each image is decoded once
and its registration handed to calib in process.

register subscribes the drone's images (the process's only image subscription) and decodes each one once,
full size and grey: calib needs the full resolution (board rows are 3-6 px apart,
``matrix_core.calib.detection``), register resizes the same grey image to its ``scale`` (its features are grey
too). register hands calib the decoded image (:meth:`DroneLink.image`), then the very registration message it
publishes on ``V/homography`` for fuse and the others (:meth:`DroneLink.registration`); calib subscribes
neither stream and pairs the two exactly as if they had come over DDS. A node alone has an unconnected link:
it decodes colour images itself and hands nothing on.

calib may run on its own thread (:meth:`DroneLink.own_thread`, calib's ``thread_niceness``): register then
queues each call and goes on with the next image, and calib's thread, niced further, calibrates when the cores
have time. On a computer shared by several drones the registrations, which fuse waits for, then go first and
calibration (which nothing in the graph waits for) fills the time left (measured with ``scripts/bench_graph.py``:
docs/running-the-graph.md). At most ``MAX_WAITING_IMAGES`` images of each drone wait for calib; when one more comes the
drone's oldest is dropped and logged (calib then warns of its registration without an image): under a load the
computer cannot carry, calib skips frames instead of falling ever further behind. The limit is per drone: a
process hosting 8 drones (``drones_per_process``) in a lockstep replay with two frames out has 16 images
waiting at times, none of them late.
"""

import collections
import threading
import time
from dataclasses import dataclass
from typing import Callable

from matrix_core.message_fields import gray_image_from_msg, image_from_msg, stamp_seconds

MAX_WAITING_IMAGES = 8  # per drone, 4 s at 2 Hz: a passing backlog; about 25 MB of 1080p images and messages


@dataclass(frozen=True)
class OwnThread:
    """A node's wish to be spun on a thread of its own (``matrix_ros.params.spin_nodes``): ``niceness`` added to
    the process's for that thread; ``waiting()`` the calls handed to it not made yet (made before it stops)."""

    niceness: int
    waiting: Callable[[], int]


class DroneLink:
    """The in-process hand-over from register to calib.

    Args:
        parameters: every parameter name of the nodes sharing the process: each node accepts the others'
            (one parameter set is given to the whole process; the names the nodes share mean the same).
    """

    def __init__(self, parameters=()):
        self.parameters = tuple(parameters)
        self._on_image = self._on_registration = None
        self._queue, self._lock, self._wake, self._node = collections.deque(), threading.Lock(), None, None

    @property
    def shared(self) -> bool:
        """Whether calib takes its images and registrations from here (instead of subscribing them)."""
        return self._on_image is not None

    def connect(self, on_image, on_registration) -> 'DroneLink':
        """calib's side: ``on_image(view, msg, image, received)`` (``received``: time.perf_counter() when register
        handed it over) and ``on_registration(view, HomographyStamped)``."""
        self._on_image, self._on_registration = on_image, on_registration
        return self

    def own_thread(self, node, niceness: int) -> OwnThread | None:
        """calib's side, once connected: with ``niceness`` >= 0 every call is queued and made on the thread that
        spins ``node`` (a guard condition wakes its executor), which runs ``niceness`` nicer; None (calls made
        at once, on register's thread) for a node alone or ``niceness`` < 0."""
        if not self.shared or niceness < 0:
            return None
        self._node, self._wake = node, node.create_guard_condition(self._make_queued_calls)
        return OwnThread(niceness, lambda: len(self._queue))

    def _call(self, fn, view: str, msg, *args) -> None:
        if self._wake is None:
            return fn(view, msg, *args)
        with self._lock:
            self._queue.append((fn, view, msg, args))
            images = [item for item in self._queue if item[0] == self._on_image and item[1] == view]
            if len(images) > MAX_WAITING_IMAGES:
                self._queue.remove(images[0])
                self._node.get_logger().warning(
                    f'{images[0][1]}: calib is {MAX_WAITING_IMAGES} images behind: the image of '
                    f't={stamp_seconds(images[0][2].header.stamp):.3f} s is not calibrated',
                    throttle_duration_sec=5.0,
                )
        self._wake.trigger()

    def _make_queued_calls(self) -> None:
        while True:
            with self._lock:
                if not self._queue:
                    return
                fn, view, msg, args = self._queue.popleft()
            fn(view, msg, *args)

    def decode(self, msg):
        """register's image: (H, W) grey full size when shared, else (H, W, 3) BGR (as a node alone decodes)."""
        return gray_image_from_msg(msg) if self.shared else image_from_msg(msg)

    def image(self, view: str, msg, image) -> None:
        """register received ``msg`` of ``view``, decoded as ``image`` (None: undecodable; calib decodes it
        itself and reports the bad input)."""
        if self.shared:
            self._call(self._on_image, view, msg, image, time.perf_counter())  # received now, whenever calib runs

    def registration(self, view: str, msg) -> None:
        """register published ``msg`` (HomographyStamped, ok or failed) for an image of ``view``."""
        if self.shared:
            self._call(self._on_registration, view, msg)
