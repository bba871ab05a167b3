"""Frame synchroniser: complete frames, timeouts for a stopped stream, ordering, late items."""

import pytest

from matrix_core.sync import FrameSynchronizer, FrameSyncSettings

STREAMS = ['D1/image', 'D2/image', 'D3/image']


def make(**kw):
    return FrameSynchronizer(FrameSyncSettings(streams=STREAMS, **kw))


def test_complete_frame_is_emitted_when_last_stream_arrives():
    sync = make()
    assert sync.add('D1/image', 1.0, 'a', now=0.0) == []
    assert sync.add('D3/image', 1.0, 'c', now=0.1) == []
    (frame,) = sync.add('D2/image', 1.0, 'b', now=0.2)
    assert frame.reason == 'complete' and frame.missing == [] and frame.stamp == 1.0
    assert frame.items == {'D1/image': 'a', 'D2/image': 'b', 'D3/image': 'c'}


def test_stopped_stream_times_out_with_the_views_that_arrived():
    sync = make(timeout=0.5)
    sync.add('D1/image', 1.0, 'a', now=10.0)
    sync.add('D2/image', 1.0, 'b', now=10.1)
    assert sync.poll(10.4) == []
    (frame,) = sync.poll(10.5)
    assert frame.reason == 'timeout' and frame.missing == ['D3/image'] and set(frame.items) == {'D1/image', 'D2/image'}
    # the stopped stream's late item is refused and counted, not silently merged
    assert sync.add('D3/image', 1.0, 'c', now=10.6) == [] and sync.late_items == 1


def test_newer_complete_frame_flushes_older_ones_in_order():
    sync = make(timeout=100)
    sync.add('D1/image', 1.0, 'a1', now=0)
    for s in STREAMS:
        out = sync.add(s, 1.5, s, now=0.1)
    assert [(f.stamp, f.reason) for f in out] == [(1.0, 'superseded'), (1.5, 'complete')]
    assert out[0].missing == ['D2/image', 'D3/image']


def test_stamp_tolerance_and_overflow():
    sync = make(stamp_tolerance=0.01, max_pending=2)
    sync.add('D1/image', 1.000, 'a', now=0)
    sync.add('D2/image', 1.005, 'b', now=0)
    assert sync.pending_stamps == [1.0]
    sync.add('D1/image', 2.0, 'x', now=0)
    out = sync.add('D1/image', 3.0, 'y', now=0)
    assert [(f.stamp, f.reason) for f in out] == [(1.0, 'overflow')]
    assert [f.stamp for f in sync.flush()] == [2.0, 3.0] and sync.pending_stamps == []


def test_bad_settings_and_streams():
    with pytest.raises(ValueError):
        FrameSyncSettings(streams=['a', 'a'])
    with pytest.raises(ValueError):
        FrameSynchronizer(FrameSyncSettings(streams=[]))
    with pytest.raises(KeyError, match='unknown stream'):
        make().add('D9/image', 1.0, None, now=0)
