"""System tests of the distributed deployment: two drone hosts and a ground station as network
namespaces (matrix_bringup.netns_harness), the real sample through calib + register (on each drone host)
and fuse (on the ground) over DDS across the links; no namespace or process is left behind.

- One drone's link cut for 5 s mid-replay and restored, discovery without multicast (fastdds_peers.xml,
  the MULTICAST flag of every interface off, no multicast discovery port bound on any host): nothing
  crashes, every frame gets tracks, the fused views say which view was missing and why, and the drone is
  back within 2 frames of its link returning; no traffic between the two drones crossed a link.
- One drone's link throttled below its image rate, and the ground's fuse process restarted mid-run
  (multicast discovery): the drone's link_sender drops frames whole at the sender (the link's queue drops
  no packet), the frames it sends are fused, latency stays bounded (nothing queues without end), and the
  restarted fuse resumes with fresh tracks.
- Discovery through a server on the ground (fastdds_client.xml, no multicast): every frame gets tracks from
  both drones, and what crosses a drone's link is its own streams and discovery, nothing of the other's."""

import os
import time

import pytest

from matrix_bringup.deployment import deployment
from matrix_bringup.distributed import SERVER_PORT, back_and_forth, read_probe, restart, start, write_replay_bag
from matrix_bringup.graph import BagFacts, GraphSettings
from matrix_bringup.netns_harness import Hosts, namespaces, unavailable

REASON = unavailable()
pytestmark = [
    pytest.mark.ros,
    pytest.mark.slow,
    pytest.mark.skipif(bool(REASON), reason=f'no network namespaces here: {REASON}'),
]
VIEWS, CUT = ['D1', 'D5'], 'D5'
FRAMES = 14  # back and forth over the sample's 5 frames
RATE = 0.5  # 1 s per frame: calib, register and fuse keep up on two loaded cores
PERIOD = 0.5 / RATE  # wall seconds between frames
# The hosts are separate computers: no process niced below another (drone_niceness is for one computer)
HOSTS = {'drone_niceness': 0}
LEAD = 5.0  # s from every player ready (matrix_bringup.start_signal) to frame 0: the start time's delivery


def _stamp(k: int) -> float:
    return round(1.0 + 0.5 * k, 6)  # the sequence clock of a written bag


def _wait(condition, timeout_s, what, procs):
    deadline = time.monotonic() + timeout_s
    while not condition():
        dead = {label: p.returncode for label, p in procs.items() if p.poll() not in (None, 0)}
        assert not dead, f'{dead} exited while waiting for {what}'
        running = sorted(label for label, p in procs.items() if p.poll() is None)
        assert time.monotonic() < deadline, f'after {timeout_s} s still waiting for {what}; running: {running}'
        time.sleep(0.1)


def _ended_cleanly(alive, players, logs, tag) -> dict:
    """Assert nothing crashed, the players finished, no log has a traceback and no namespace is left behind;
    returns the logs' texts by file name."""
    logs_text = {p.name: p.read_text() for p in logs.glob('*.log')}
    assert all(code is None for code in alive.values()), alive
    assert all(p.returncode == 0 for p in players.values()), logs_text
    assert not any('Traceback' in text for text in logs_text.values()), logs_text
    assert namespaces(owner_pid=int(tag[3:])) == []
    return logs_text


def test_link_cut_and_restored_mid_replay(matrix_sample, tmp_path):
    bag = write_replay_bag(matrix_sample, tmp_path / 'bag', VIEWS, back_and_forth(5, FRAMES))
    settings = GraphSettings(
        bag=str(bag),
        dataset=str(matrix_sample),
        views=VIEWS,
        lockstep=False,
        rate=RATE,
        sync_timeout=1.5,
        **HOSTS,
        record=str(tmp_path / 'rec'),
    )
    d = deployment(settings, BagFacts.read(str(bag), VIEWS))
    logs = tmp_path / 'logs'
    with Hosts(VIEWS, multicast=False) as hosts:
        procs = start(d, hosts, logs, discovery='peers', image_probes=[CUT], captures=['D1'], player_lead_s=LEAD)
        fused = lambda: {
            line['stamp']: line
            for line in read_probe(logs / 'ground_probe.log')  # noqa: E731
            if line['kind'] == 'fuse'
        }
        _wait(lambda: _stamp(2) in fused(), 240, 'frame 2 fused (start-up and discovery)', procs)
        # discovery went unicast: nobody listens on the multicast port of the domain, the ground on its unicast
        ports = {h: hosts.udp_ports(h) for h in hosts.hosts}
        hosts.cut(CUT)
        cut_at = time.time()
        time.sleep(5.0)  # what is tested: a 5 s outage
        hosts.restore(CUT)
        restored_at = time.time()
        players = {label: p for label, p in procs.items() if label.endswith('bag_player')}
        _wait(lambda: all(p.poll() is not None for p in players.values()), 300, 'the players to finish', procs)
        _wait(lambda: _stamp(FRAMES - 1) in fused(), 120, 'the last frame fused', procs)
        alive = {label: p.poll() for label, p in procs.items() if label not in players}
        udp = {h: hosts.udp_errors(h) for h in hosts.hosts}
        hosts.stop_all()
        tag = hosts.tag
    print('UDP receive errors per host:', udp)
    logs_text = _ended_cleanly(alive, players, logs, tag)

    domain = int(os.environ.get('ROS_DOMAIN_ID', '0'))
    assert not any(7400 + 250 * domain in p for p in ports.values()), ports  # RTPS well-known ports
    assert 7400 + 250 * domain + 10 in ports['ground'], ports  # the unicast discovery of participant 0
    # the drones announce themselves to the ground only: no drone found another, nothing crossed between them
    crossed = read_probe(logs / 'D1_capture.log')[-1]['streams']
    assert any(r['peer'] == 'ground' and r['stream'] == '/D1/link/image/compressed' for r in crossed), crossed
    # (the camera's own stream stays on the drone: its readers there are calib, register and link_sender)
    assert not any(r['stream'] == '/D1/image/compressed' and r['kind'] == 'data' for r in crossed), crossed
    assert not [r for r in crossed if r['peer'] == CUT], crossed

    lines = read_probe(logs / 'ground_probe.log')
    tracks = [line['stamp'] for line in lines if line['kind'] == 'tracks']
    status = {line['stamp']: line for line in lines if line['kind'] == 'fuse'}
    published = {line['stamp']: line['t'] for line in read_probe(logs / f'{CUT}_probe.log') if line['kind'] == 'image'}
    stamps = [_stamp(k) for k in range(FRAMES)]
    assert sorted(tracks) == stamps and tracks == sorted(tracks), tracks  # every frame once, in order
    views_used = [status[s]['views_used'] for s in stamps]
    # the frames whose D5 image left during the cut were fused with D1 alone; the diagnostics say why
    cut = [s for s in stamps if cut_at + 0.2 < published[s] < restored_at - 0.2]
    assert len(cut) >= 3, (cut_at, restored_at, published)
    for s in cut:  # (the frame before the restore may get its homography late, resent: 'no image')
        assert status[s]['views_used'] == 1 and set(status[s]['missing']) == {CUT}, status[s]
        assert status[s]['missing'][CUT].startswith('missing: no image'), status[s]
    assert sum(status[s]['missing'][CUT] == 'missing: no image and no homography' for s in cut) >= 3
    # what the reliable homography stream resent after the restore was of frames already fused: refused
    assert (
        'D5: geometry at t=' in logs_text['fuse.log']
        and 'arrived after its frame was fused; ignored' in logs_text['fuse.log']
    ), logs_text['fuse.log']
    # back within 2 frames of the link returning: the third frame published after it, and all later ones
    after = [s for s in stamps if published[s] > restored_at]
    assert len(after) >= 4, (restored_at, published)
    assert all(status[s]['views_used'] == 2 for s in after[2:]), [(s, status[s]) for s in after]
    assert all(status[s]['views_used'] == 2 for s in stamps if published[s] < cut_at - 0.5), views_used


def test_throttled_link_and_fuse_restarted(matrix_sample, tmp_path):
    frames, slow, rate_mbit = 45, 'D1', 4.0  # D1's images need 6 Mbit/s at 1 frame/s: it gets 4
    # (45 frames: a restarted fuse process took up to 26 s to load on two loaded cores)
    bag = write_replay_bag(matrix_sample, tmp_path / 'bag', VIEWS, back_and_forth(5, frames))
    # (a sync timeout of 2.5 s: one of D1's 0.75 MB images takes 1.6 s to cross at 4 Mbit/s)
    settings = GraphSettings(
        bag=str(bag), dataset=str(matrix_sample), views=VIEWS, lockstep=False, rate=RATE, sync_timeout=2.5, **HOSTS
    )
    # D1's images may use 90 % of its link (the rest: geometry, diagnostics, discovery); D5's is not limited
    d = deployment(settings, BagFacts.read(str(bag), VIEWS), link_mbit={slow: 0.9 * rate_mbit})
    logs, other = tmp_path / 'logs', next(v for v in VIEWS if v != slow)
    with Hosts(VIEWS) as hosts:
        hosts.limit(slow, rate_mbit)
        procs = start(d, hosts, logs, discovery='multicast', image_probes=[other], player_lead_s=LEAD)
        fused = lambda: {
            line['stamp']
            for line in read_probe(logs / 'ground_probe.log')  # noqa: E731
            if line['kind'] == 'fuse'
        }
        _wait(lambda: _stamp(3) in fused(), 240, 'frame 3 fused', procs)
        first_fuse = procs.pop('fuse')
        assert hosts.stop(first_fuse) == 0
        stopped_at = time.time()
        procs['fuse'] = restart(d, hosts, logs, 'fuse')
        players = {label: p for label, p in procs.items() if label.endswith('bag_player')}
        _wait(lambda: all(p.poll() is not None for p in players.values()), 300, 'the players to finish', procs)
        _wait(lambda: _stamp(frames - 1) in fused(), 120, 'the last frame fused', procs)
        link = hosts.link_bytes(slow)
        alive = {label: p.poll() for label, p in procs.items() if label not in players}
        hosts.stop_all()
        tag = hosts.tag
    logs_text = _ended_cleanly(alive, players, logs, tag)

    lines = read_probe(logs / 'ground_probe.log')
    tracks = {line['stamp']: line for line in lines if line['kind'] == 'tracks'}
    status = {line['stamp']: line for line in lines if line['kind'] == 'fuse'}
    published = {
        line['stamp']: line['t'] for line in read_probe(logs / f'{other}_probe.log') if line['kind'] == 'image'
    }
    # throttled: D1's link_sender let a frame go only once the ones before had time to cross and dropped the
    # others whole at the sender, so the link's queue dropped no packet and the frames sent were fused with both
    # views (before link_sender the queue dropped packets of every frame: 1 frame in 30 arrived whole);
    # frames without D1's image went out after the sync timeout with the other view, saying why
    sender = [line['outcome'] for line in lines if line['kind'] == 'link' and line['view'] == slow]
    assert link['dropped'] == 0, link
    assert sender.count('dropped') >= frames // 5 and sender.count('sent') >= frames // 5, sender
    both = [s for s in status if status[s]['views_used'] == 2]
    assert len(both) >= frames // 5, (sender, [status[s] for s in sorted(status)])
    # the frames D1 did not send went out with D5 alone, saying why, as soon as D1's notice and geometry came:
    # fuse did not wait its sync timeout for an image D1 had said would not come
    dropped = {line['stamp'] for line in lines if line['kind'] == 'link' and line['outcome'] == 'dropped'}
    told = [
        s
        for s in status
        if s in dropped
        and s in published
        and s in tracks
        and status[s]['missing'].get(slow) == 'missing: no image: dropped at the sender (link budget)'
    ]
    assert len(told) >= frames // 5, [status[s] for s in sorted(status)]
    waited = sorted(tracks[s]['t'] - published[s] for s in told)
    assert waited[len(waited) // 2] < settings.sync_timeout - 1.0, waited
    # (D1's images would fall 1 frame behind every 3 in a queue without end: 15 s by the last frame. What
    # latency there is, is fuse waiting sync_timeout for D1 plus the machine's load: 1.7-5.9 s seen on two
    # cores shared with other work, the last frames' no higher than the first ones')
    latency = [tracks[s]['t'] - published[s] for s in sorted(tracks) if s in published]
    assert max(latency) < 10.0 and sorted(latency[-10:])[5] < settings.sync_timeout + 3.0, latency
    # restarted: the first fuse process published the frames before it stopped, the second one resumes with
    # the frames after it (its tracker fresh: ids from 1) and fuses both views when the link lets it
    before = [s for s in tracks if tracks[s]['t'] < stopped_at]
    after = sorted(s for s in tracks if tracks[s]['t'] > stopped_at)
    assert len(before) >= 3 and 'published' in logs_text['fuse.log'], logs_text['fuse.log'][-2000:]
    assert len(after) >= 4 and after[-1] == _stamp(frames - 1) and min(after) > max(before), (before, after)
    resumed_ids = [i for s in after for i in tracks[s]['ids']]
    assert resumed_ids and min(resumed_ids) == 1, [tracks[s]['ids'] for s in after]
    # (its first frames may have no image: they left before its image subscriptions matched, which took up
    # to 2 frames on two loaded cores; from its first image on, every frame has one)
    first = next(i for i, s in enumerate(after) if status[s]['views_used'] >= 1)
    assert first <= 3 and all(status[s]['views_used'] >= 1 for s in after[first:]), [status[s] for s in after]


def test_discovery_server_without_multicast(matrix_sample, tmp_path):
    frames, watched, other = 10, 'D1', 'D5'
    bag = write_replay_bag(matrix_sample, tmp_path / 'bag', VIEWS, back_and_forth(5, frames))
    settings = GraphSettings(
        bag=str(bag), dataset=str(matrix_sample), views=VIEWS, lockstep=False, rate=RATE, sync_timeout=1.5, **HOSTS
    )
    d = deployment(settings, BagFacts.read(str(bag), VIEWS))
    logs = tmp_path / 'logs'
    with Hosts(VIEWS, multicast=False) as hosts:
        procs = start(d, hosts, logs, discovery='server', image_probes=VIEWS, captures=[watched], player_lead_s=LEAD)
        fused = lambda: {
            line['stamp']
            for line in read_probe(logs / 'ground_probe.log')  # noqa: E731
            if line['kind'] == 'fuse'
        }
        players = {label: p for label, p in procs.items() if label.endswith('bag_player')}
        _wait(lambda: all(p.poll() is not None for p in players.values()), 300, 'the players to finish', procs)
        _wait(lambda: _stamp(frames - 1) in fused(), 120, 'the last frame fused', procs)
        ports = {h: hosts.udp_ports(h) for h in hosts.hosts}
        alive = {label: p.poll() for label, p in procs.items() if label not in players}
        hosts.stop_all()
        tag = hosts.tag
    _ended_cleanly(alive, players, logs, tag)

    domain = int(os.environ.get('ROS_DOMAIN_ID', '0'))
    assert SERVER_PORT in ports['ground'], ports  # the server listens on the ground ...
    assert not any(7400 + 250 * domain in p for p in ports.values()), ports  # ... and nobody on multicast
    lines = read_probe(logs / 'ground_probe.log')
    tracks = [line['stamp'] for line in lines if line['kind'] == 'tracks']
    status = {line['stamp']: line for line in lines if line['kind'] == 'fuse'}
    stamps = [_stamp(k) for k in range(frames)]
    assert sorted(tracks) == stamps and tracks == sorted(tracks), tracks  # every frame once, in order
    # both drones found through the server: the images each published reached fuse (most of them: on a loaded
    # machine one may come after its sync timeout; frames also miss homographies computed too late)
    for view in VIEWS:
        published = {line['stamp'] for line in read_probe(logs / f'{view}_probe.log') if line['kind'] == 'image'}
        arrived = [s for s in published if 'no image' not in status[s]['missing'].get(view, '')]
        assert published and len(arrived) >= len(published) / 2, (view, published, status)
    # D1's link: link_sender's images and the geometry go up to the ground, the camera's stream stays on the
    # drone; none of D5's streams crosses it either way
    crossed = read_probe(logs / f'{watched}_capture.log')[-1]['streams']
    up = {(r['stream'], r['kind']) for r in crossed if r['direction'] == 'up' and r['peer'] == 'ground'}
    assert {('/D1/link/image/compressed', 'data'), ('/D1/homography', 'data')} <= up, crossed
    assert ('/D1/image/compressed', 'data') not in up, crossed
    assert not [r for r in crossed if r['stream'].startswith(f'/{other}/')], crossed
    assert not [
        r
        for r in crossed
        if r['direction'] == 'down' and r['kind'] == 'data' and r['stream'].endswith('image/compressed')
    ], crossed
