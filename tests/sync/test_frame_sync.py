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
    assert frame.first_arrival == 0.0  # when its first item came: how long the frame waited (fuse diagnostics)


def test_stopped_stream_times_out_with_the_views_that_arrived():
    sync = make(timeout=0.5)
    sync.add('D1/image', 1.0, 'a', now=10.0)
    sync.add('D2/image', 1.0, 'b', now=10.1)
    assert sync.poll(10.4) == []
    (frame,) = sync.poll(10.5)
    assert frame.reason == 'timeout' and frame.missing == ['D3/image'] and set(frame.items) == {'D1/image', 'D2/image'}
    assert frame.first_arrival == 10.0
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


def test_duplicated_and_out_of_order_stamps_never_mix_frames():
    """A stamp sent twice by a stream keeps one item per stream (the later one), an item older
    than the last emitted frame is refused and counted, and a frame never takes an item of another stamp."""
    sync = make(timeout=100)
    sync.add('D1/image', 1.0, 'a', now=0)
    sync.add('D1/image', 1.0, 'a again', now=0)  # duplicate while the frame waits
    sync.add('D2/image', 1.0, 'b', now=0)
    (frame,) = sync.add('D3/image', 1.0, 'c', now=0)
    assert frame.items == {'D1/image': 'a again', 'D2/image': 'b', 'D3/image': 'c'}
    assert sync.add('D2/image', 1.0, 'b again', now=0) == [] and sync.late_items == 1  # after its frame
    sync.add('D1/image', 2.0, 'x', now=0)
    sync.add('D1/image', 1.5, 'y', now=0)  # out of order, still pending: a frame of its own
    assert sync.pending_stamps == [1.5, 2.0]
    out = [f for s in STREAMS[1:] for f in sync.add(s, 2.0, s, now=0)]
    assert [(f.stamp, f.reason, sorted(f.items)) for f in out] == [
        (1.5, 'superseded', ['D1/image']),
        (2.0, 'complete', STREAMS),
    ]
    assert sync.add('D3/image', 1.5, 'late', now=0) == [] and sync.late_items == 2


def test_a_stopped_drone_resumes():
    sync = make(timeout=0.5)
    for k, stamp in enumerate((1.0, 1.5, 2.0)):
        for s in STREAMS[:2]:  # D3 stopped
            sync.add(s, stamp, s, now=10.0 + k)
        (frame,) = sync.poll(10.5 + k)
        assert frame.reason == 'timeout' and frame.missing == ['D3/image']
    out = [f for s in STREAMS for f in sync.add(s, 2.5, s, now=13.0)]  # D3 is back
    assert [(f.stamp, f.reason, f.missing) for f in out] == [(2.5, 'complete', [])]


def test_time_going_back_starts_a_new_sequence_only_beyond_restart_gap():
    """As the calib node does: its drone's StampRestart (fed what it processed) tells the synchroniser."""
    from matrix_core.sync import StampRestart

    sync, restart = make(timeout=100), StampRestart(2.0)

    def add(stream, stamp, item):
        out = []
        if restart.is_back(stamp):
            out = sync.restart()  # the old run's pending frames, processed as the old run's
            for frame in out:
                restart.went_back(frame.stamp)
            assert restart.went_back(stamp)  # the new run starts here
        new = sync.add(stream, stamp, item, now=0)
        for frame in new:
            restart.went_back(frame.stamp)  # processed
        return out + new

    for s in STREAMS:
        add(s, 10.0, s)
    add('D1/image', 10.5, 'pending')
    assert add('D1/image', 9.0, 'late') == [] and sync.late_items == 1  # 1 s back: late
    out = add('D1/image', 1.0, 'new run')  # 9 s back: a restart
    assert [(f.stamp, f.reason) for f in out] == [(10.5, 'restart')] and sync.restarts == 1
    assert sync.pending_stamps == [1.0]
    out = [f for s in STREAMS[1:] for f in add(s, 1.0, s)]
    assert [(f.stamp, f.reason) for f in out] == [(1.0, 'complete')]
    assert out[0].items['D1/image'] == 'new run'
    with pytest.raises(ValueError):
        StampRestart(0)


def test_stamp_restart():
    from matrix_core.sync import StampRestart

    r = StampRestart(2.0)
    assert [r.went_back(t) for t in (1.0, 5.0, 4.0, 3.5, 1.0, 1.5, 9.0, 6.9)] == [
        False,
        False,
        False,
        False,
        True,
        False,
        False,
        True,
    ]


def test_waiting_before_says_whether_an_earlier_frame_is_pending():
    # fuse defers decoding a later frame's images while an earlier frame still waits for its homographies
    sync = make(stamp_tolerance=0.01)
    assert not sync.waiting_before(1.0)
    sync.add('D1/image', 1.0, 'a', now=0.0)
    assert not sync.waiting_before(1.0) and not sync.waiting_before(1.005)  # the same frame, within tolerance
    assert sync.waiting_before(1.5) and not sync.waiting_before(0.5)
    sync.add('D2/image', 1.0, 'b', now=0.1)
    sync.add('D3/image', 1.0, 'c', now=0.2)  # complete: emitted, nothing earlier waits any more
    assert not sync.waiting_before(1.5)
