"""Discovery through a server on the ground, clients made by Fast DDS from ``ROS_DISCOVERY_SERVER`` (the
'server_env' way of matrix_bringup.distributed), on hosts whose links carry no multicast; and what crosses a
link by DDS stream (matrix_bringup.link_capture): a real talker on D1, listeners on the ground and on D2."""

import json
import os
import sys
import time

import pytest

from matrix_bringup.distributed import SERVER_PORT, host_env, read_probe
from matrix_bringup.netns_harness import GROUND, Hosts, unavailable

REASON = unavailable()
pytestmark = [
    pytest.mark.ros,
    pytest.mark.slow,
    pytest.mark.skipif(bool(REASON), reason=f'no network namespaces here: {REASON}'),
]

MESSAGES = 60
DEADLINE_S = 180.0  # a safety net only: the talker starts on its readers' match, the readers stop on its messages
# The talker publishes once both listeners matched (found through the server), so none of its messages goes
# before a reader is there; each listener stops once it got them all (the histories hold all: none is lost).
TALK = (
    'import sys, time, rclpy\nfrom rclpy.duration import Duration\nfrom std_msgs.msg import String\nrclpy.init()\n'
    'n = rclpy.create_node("talker")\np = n.create_publisher(String, "/D1/chat", 100)\n'
    'end = time.monotonic() + float(sys.argv[2])\n'
    'while p.get_subscription_count() < 2 and time.monotonic() < end:\n    time.sleep(0.1)\n'
    'for i in range(int(sys.argv[1])):\n    p.publish(String(data="x" * 2000))\n    time.sleep(0.2)\n'
    'p.wait_for_all_acked(Duration(seconds=30.0))\n'
)
LISTEN = (
    'import sys, time, json, rclpy\nfrom std_msgs.msg import String\nrclpy.init()\n'
    'n = rclpy.create_node("listener")\ngot = []\n'
    'n.create_subscription(String, "/D1/chat", lambda m: got.append(len(m.data)), 100)\n'
    'end = time.monotonic() + float(sys.argv[2])\n'
    'while len(got) < int(sys.argv[1]) and time.monotonic() < end:\n    rclpy.spin_once(n, timeout_sec=0.1)\n'
    'print(json.dumps({"got": len(got)}), flush=True)\n'
)


def _wait_for(condition, what: str):
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        assert time.monotonic() < deadline, f'after {DEADLINE_S} s still waiting for {what}'
        time.sleep(0.1)


def test_server_from_environment_and_streams_captured(tmp_path):
    env = host_env('server_env')
    assert env['ROS_DISCOVERY_SERVER'].endswith(f':{SERVER_PORT}')
    with Hosts(['D1', 'D2'], multicast=False) as hosts:
        names = [f'{h}={hosts.address(h)}' for h in hosts.hosts]
        capture = hosts.start(
            'D1',
            [sys.executable, '-m', 'matrix_bringup.link_capture', '--hosts', *names],
            tmp_path / 'capture.log',
            env,
        )
        hosts.start(GROUND, [sys.executable, '-m', 'matrix_bringup.discovery_server'], tmp_path / 'server.log', env)
        # the capture sees the link from before the first DDS packet
        _wait_for(lambda: read_probe(tmp_path / 'capture.log') or capture.poll() is not None, 'the capture')
        assert capture.poll() is None, (tmp_path / 'capture.log').read_text()
        args = [str(MESSAGES), str(DEADLINE_S)]
        listeners = {
            h: hosts.start(h, [sys.executable, '-c', LISTEN, *args], tmp_path / f'listen_{h}.log', env)
            for h in (GROUND, 'D2')
        }
        talker = hosts.start('D1', [sys.executable, '-c', TALK, *args], tmp_path / 'talk.log', env)
        assert talker.wait(2 * DEADLINE_S) == 0, (tmp_path / 'talk.log').read_text()
        for h, p in listeners.items():
            assert p.wait(2 * DEADLINE_S) == 0, (tmp_path / f'listen_{h}.log').read_text()
        ports = {h: hosts.udp_ports(h) for h in hosts.hosts}
        hosts.stop(capture)
    got = {h: json.loads((tmp_path / f'listen_{h}.log').read_text().splitlines()[-1])['got'] for h in listeners}
    assert all(n == MESSAGES for n in got.values()), got  # both found the talker through the server
    domain = int(os.environ.get('ROS_DOMAIN_ID', '0'))
    assert SERVER_PORT in ports[GROUND] and not any(7400 + 250 * domain in p for p in ports.values()), ports

    streams = read_probe(tmp_path / 'capture.log')[-1]['streams']
    by = {(r['direction'], r['peer'], r['stream'], r['kind']): r for r in streams}
    for peer in (GROUND, 'D2'):  # ~2 kB a message: every message a reader got crossed D1's link to it
        assert by[('up', peer, '/D1/chat', 'data')]['bytes'] > got[peer] * 2000, (got, streams)
        assert by[('down', peer, '/D1/chat', 'acknowledgements')]['frames'] > 10, streams  # reliable readers
    assert ('down', GROUND, 'discovery: endpoints (SEDP)', '') in by, streams  # from the server
    assert not [r for r in streams if r['peer'] == 'multicast' and r['stream'].startswith('discovery')], streams
