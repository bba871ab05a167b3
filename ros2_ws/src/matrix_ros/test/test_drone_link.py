"""The in-process hand-over from register to calib (``matrix_ros.drone_link``) when calib has a thread of its
own: the calls wait in order until calib's thread makes them, a drone's oldest image is dropped (logged) when
more than ``MAX_WAITING_IMAGES`` of its images wait, ``received`` is when register handed an image over, and a
process spun by ``spin_nodes`` makes every call still waiting before it exits. Real rclpy: guard conditions and
executors."""

import threading
import time

import pytest
import rclpy
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from matrix_core.message_fields import stamp_seconds
from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.drone_link import MAX_WAITING_IMAGES, DroneLink
from matrix_ros.params import _spin_in_thread

pytestmark = pytest.mark.ros


def _image(t: float) -> CompressedImage:
    return CompressedImage(header=Header(stamp=seconds_to_stamp(t)), format='jpeg')


def _registration(t: float) -> Header:  # the link reads only the header: any stamped message stands in
    return Header(stamp=seconds_to_stamp(t))


def _linked(calls: list) -> DroneLink:
    return DroneLink().connect(
        lambda view, msg, image, received: calls.append(
            ('image', stamp_seconds(msg.header.stamp), received, threading.get_ident())
        ),
        lambda view, msg: calls.append(('registration', stamp_seconds(msg.stamp), None, threading.get_ident())),
    )


def _drain(node, own):
    """Spin calib's own thread until no call waits (at most 20 s), stop it; returns the joined thread."""
    stop = []
    thread = _spin_in_thread(node, own, stop)
    end = time.monotonic() + 20
    while own.waiting() and time.monotonic() < end:
        time.sleep(0.01)
    stop.append(True)
    thread.join(20)
    return thread


@pytest.fixture
def node():
    rclpy.init()
    node = rclpy.create_node('drone_link_test')
    yield node
    node.destroy_node()
    rclpy.shutdown()


def test_without_a_thread_of_its_own_calls_are_made_at_once(node):
    calls = []
    assert DroneLink().own_thread(node, 5) is None  # a node alone: no link to hand over on
    link = _linked(calls)
    assert link.own_thread(node, -1) is None
    link.image('D1', _image(1.0), object())
    link.registration('D1', _registration(1.0))
    assert [c[:2] for c in calls] == [('image', 1.0), ('registration', 1.0)]
    assert all(c[3] == threading.get_ident() for c in calls)


def test_calls_wait_in_order_for_calibs_thread_and_the_oldest_images_drop(node):
    calls = []
    link = _linked(calls)
    own = link.own_thread(node, 3)
    assert own.niceness == 3
    frames, handed = MAX_WAITING_IMAGES + 2, {}
    for k in range(frames):
        handed[k] = time.perf_counter()
        link.image('D1', _image(float(k)), object())
        link.registration('D1', _registration(float(k)))
    assert calls == [] and own.waiting() == 2 * frames - 2  # nothing made yet; the 2 oldest images dropped
    thread = _drain(node, own)
    assert not thread.is_alive() and thread.error is None
    made = [c[:2] for c in calls]
    assert made == [
        c for k in range(frames) for c in ([('image', float(k))] if k >= 2 else []) + [('registration', float(k))]
    ], made
    assert all(c[3] == thread.ident for c in calls)  # all on calib's own thread
    for kind, t, received, _ in calls:  # an image's time is when register handed it over
        assert kind == 'registration' or received == pytest.approx(handed[int(t)], abs=0.01)


def test_the_limit_of_waiting_images_is_per_drone(node):
    """A process of several drones (drones_per_process) queues MAX_WAITING_IMAGES images of EACH before any
    is dropped: a lockstep replay with two frames out has 2 per drone waiting, 16 in an 8-drone process."""
    calls = []
    link = _linked(calls)
    own = link.own_thread(node, 3)
    views = [f'D{i}' for i in range(1, 9)]
    for k in range(MAX_WAITING_IMAGES):
        for view in views:
            link.image(view, _image(float(k)), object())
    assert own.waiting() == MAX_WAITING_IMAGES * len(views)  # none dropped
    link.image('D3', _image(99.0), object())
    assert own.waiting() == MAX_WAITING_IMAGES * len(views)  # D3's oldest made room for its newest
    _drain(node, own)
    made = sorted(c[1] for c in calls)
    assert len(made) == MAX_WAITING_IMAGES * len(views) and made.count(0.0) == len(views) - 1 and 99.0 in made


def test_the_own_thread_makes_the_calls_still_waiting_when_it_stops(node):
    calls = []
    link = _linked(calls)
    own = link.own_thread(node, 0)
    for k in range(3):
        link.image('D1', _image(float(k)), object())
        link.registration('D1', _registration(float(k)))
    thread = _spin_in_thread(node, own, [True])  # stopped before it ever ran: the calls are made all the same
    thread.join(20)
    assert len(calls) == 6 and own.waiting() == 0
