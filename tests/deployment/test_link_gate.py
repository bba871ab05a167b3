"""matrix_core.link_gate: a frame crosses a link only once the frames before it have had time to; the others
are dropped whole at the sender."""

import pytest

from matrix_core.link_gate import DROPPED, SENT, WIRE_OVERHEAD, LinkGate

FRAME = 745_000  # bytes: a 1080p JPEG of the real sample


def test_a_frame_occupies_the_link_for_its_bytes_at_the_link_rate():
    gate = LinkGate(link_mbit=4.0)
    assert gate.transfer_s(FRAME) == pytest.approx(FRAME * WIRE_OVERHEAD * 8 / 4e6)  # 1.54 s
    assert gate.offer(10.0, FRAME) == SENT and gate.busy_s(10.0) == pytest.approx(1.542, abs=1e-3)
    assert gate.offer(11.0, FRAME) == DROPPED  # the first one still on its way
    assert gate.offer(11.55, 1000) == SENT  # free again
    assert gate.busy_s(11.55) == pytest.approx(1000 * WIRE_OVERHEAD * 8 / 4e6)
    assert (gate.counts.sent, gate.counts.dropped, gate.counts.sent_bytes) == (2, 1, FRAME + 1000)


@pytest.mark.parametrize('link_mbit, every', [(4.0, 2), (2.0, 4), (20.0, 1)])
def test_a_link_slower_than_the_camera_carries_one_frame_in_so_many(link_mbit, every):
    # the camera at 1 frame/s, as in the throttled system test; 6.2 Mbit/s of images
    gate = LinkGate(link_mbit)
    outcomes = [gate.offer(1.0 * k, FRAME) for k in range(12)]
    assert outcomes == ([SENT] + [DROPPED] * (every - 1)) * (12 // every)


def test_without_a_budget_every_frame_leaves():
    gate = LinkGate(link_mbit=0.0)
    assert [gate.offer(0.001 * k, FRAME) for k in range(5)] == [SENT] * 5
    assert gate.transfer_s(FRAME) == 0.0 and gate.busy_s(0.004) == 0.0


def test_the_rate_must_not_be_negative():
    with pytest.raises(ValueError, match='link_mbit'):
        LinkGate(-1.0)
