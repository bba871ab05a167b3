"""The bag player's lockstep bookkeeping (matrix_ros.lockstep.LockstepWindow): which frames may leave and
which count as timed out. The graph is played by a function that releases frames as a slow graph would."""

import pytest
from std_msgs.msg import Header

from matrix_ros.conversions import seconds_to_stamp
from matrix_ros.lockstep import LockstepWindow


class Graph:
    """Finishes the oldest frame it was sent and has not finished, one per spin; a frame in ``stuck`` never
    finishes (the next ones do)."""

    def __init__(self, stuck=()):
        self.window, self.stuck, self.sent, self.log = None, set(stuck), [], []

    def spin_for(self, seconds, until):
        while not until():
            pending = [s for s in self.sent if s not in self.window.released]
            ready = [s for s in pending if s not in self.stuck]
            if not ready:
                return  # nothing the graph could finish: the wait times out
            self.window.on_message(Header(stamp=seconds_to_stamp(ready[0])))
            self.log.append((ready[0], len(pending)))  # the frame, and how many were out until then


def _window(size, graph):
    warnings = []
    window = LockstepWindow(size, 1, 5.0, graph.spin_for, warnings.append)
    graph.window = window
    return window, warnings


def _play(window, graph, stamps):
    for stamp in stamps:
        graph.sent.append(stamp)  # published: the graph may now finish it
        window.sent(stamp, f'frame at {stamp}')
    window.finish()


@pytest.mark.parametrize('size', [1, 2, 3])
def test_at_most_window_frames_are_out(size):
    graph = Graph()
    window, warnings = _window(size, graph)
    _play(window, graph, [1.0, 1.5, 2.0, 2.5, 3.0])
    assert [s for s, _ in graph.log] == [1.0, 1.5, 2.0, 2.5, 3.0] and not warnings and not window.out
    # `size` frames were out whenever one was released (fewer at the end: no more to send)
    assert [n for _, n in graph.log] == [min(size, 5 - i) for i in range(5)]


def test_a_frame_never_released_times_out_and_the_rest_go_on():
    graph = Graph(stuck={1.5})
    window, warnings = _window(2, graph)
    _play(window, graph, [1.0, 1.5, 2.0])
    assert window.timed_out == [1.5] and len(warnings) == 1 and 'frame at 1.5' in warnings[0]
    assert [s for s, _ in graph.log] == [1.0, 2.0] and not window.out
    assert warnings[0].startswith('lockstep: only 0/1 messages')  # what bench_graph.py looks for in the log


def test_stamped_messages_release_their_frame():
    window, _ = _window(1, Graph())
    window.on_message(Header(stamp=seconds_to_stamp(2.5)))
    window.on_message(Header(stamp=seconds_to_stamp(2.5000001)))  # the same frame (rounded to 1 us)
    assert window.released == {2.5: 2}
    with pytest.raises(ValueError, match='window'):
        LockstepWindow(0, 1, 5.0, None, print)
