"""The network-namespace hosts (matrix_bringup.netns_harness): hosts reach each other over their links, a cut
link passes nothing until restored, limits are applied, and nothing is left behind (namespaces, links,
processes): on leaving normally, on an exception, and after the owning process was SIGKILLed."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from matrix_bringup.netns_harness import GROUND, Hosts, namespaces, remove_stale, unavailable

REASON = unavailable()
pytestmark = [pytest.mark.slow, pytest.mark.skipif(bool(REASON), reason=f'no network namespaces here: {REASON}')]

# Binds, says so, then waits for SIGUSR1 (sent once the sender is done) and reads what its socket holds, waiting
# a moment more for a datagram still crossing (blocked first: a signal before the wait is kept, not fatal).
RECEIVE = (
    'import signal, socket, sys; signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGUSR1}); '
    's = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("", 47001)); print("ready", flush=True); '
    'signal.sigwait({signal.SIGUSR1}); s.settimeout(float(sys.argv[1]))\n'
    'try:\n    print(s.recv(100).decode(), flush=True)\nexcept TimeoutError:\n    print("nothing", flush=True)'
)
SEND = (
    'import socket, sys, time\nfor _ in range(20):\n    socket.socket(socket.AF_INET, socket.SOCK_DGRAM)'
    '.sendto(b"hello", (sys.argv[1], 47001)); time.sleep(0.05)'
)
DEADLINE_S = 120.0  # a safety net only: every wait below ends on an event (a line, an exit, a process state)


def _wait_for(condition, what: str):
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        assert time.monotonic() < deadline, f'after {DEADLINE_S} s still waiting for {what}'
        time.sleep(0.05)


def _reaches(hosts: Hosts, src: str, dst: str, tmp_path: Path) -> bool:
    """A UDP datagram from host ``src`` arrives at host ``dst``: the receiver is bound before the sender starts
    and reads once the sender has sent all its datagrams."""
    log = tmp_path / f'recv_{src}_{dst}_{time.monotonic_ns()}.log'
    receiver = hosts.start(dst, [sys.executable, '-c', RECEIVE, '1.0'], log)
    _wait_for(lambda: 'ready' in log.read_text().splitlines()[1:] or receiver.poll() is not None, 'the receiver')
    assert receiver.poll() is None, log.read_text()
    sender = hosts.start(src, [sys.executable, '-c', SEND, hosts.address(dst)], tmp_path / 'send.log')
    assert sender.wait(DEADLINE_S) == 0, (tmp_path / 'send.log').read_text()
    receiver.send_signal(signal.SIGUSR1)
    assert receiver.wait(DEADLINE_S) == 0, log.read_text()
    return 'hello' in log.read_text().splitlines()[1:]


def _alive(pids) -> list:
    """Those of ``pids`` still running (a zombie counts as gone)."""

    def running(pid):
        try:
            return Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0] != 'Z'
        except OSError:
            return False

    return [p for p in pids if running(p)]


def _in_namespaces(hosts: Hosts, at_least: int = 0) -> list:
    """pids of every process in the hosts' namespaces (``ip netns pids``), once there are ``at_least`` (a
    process just started may not have entered its namespace yet: ``ip netns exec`` joins it, then execs)."""

    def pids():
        return [
            int(p)
            for h in hosts.hosts
            for p in subprocess.run(['ip', 'netns', 'pids', hosts.ns(h)], capture_output=True, text=True).stdout.split()
        ]

    _wait_for(lambda: len(pids()) >= at_least, f'{at_least} processes in the namespaces')
    return pids()


def test_links_cut_restore_limit_and_nothing_left(tmp_path):
    with Hosts(['D1', 'D2'], rate_mbit=20) as hosts:
        assert sorted(namespaces(owner_pid=None)) >= sorted(hosts.ns(h) for h in hosts.hosts)
        sleeper = hosts.start('D1', ['sleep', '600'], tmp_path / 'sleep.log')
        assert _reaches(hosts, 'D1', GROUND, tmp_path) and _reaches(hosts, GROUND, 'D2', tmp_path)
        assert _reaches(hosts, 'D1', 'D2', tmp_path)  # drones see each other through the ground's bridge
        hosts.cut('D1')
        assert not _reaches(hosts, 'D1', GROUND, tmp_path) and not _reaches(hosts, GROUND, 'D1', tmp_path)
        assert _reaches(hosts, 'D2', GROUND, tmp_path)  # the other drone's link is untouched
        hosts.restore('D1')
        assert _reaches(hosts, 'D1', GROUND, tmp_path)
        qdisc = subprocess.run(
            ['ip', 'netns', 'exec', hosts.ns('D2'), 'tc', 'qdisc', 'show', 'dev', 'eth0'],
            capture_output=True,
            text=True,
        ).stdout
        assert 'tbf' in qdisc and '20Mbit' in qdisc, qdisc
        stats = hosts.link_bytes('D1')
        assert stats['up'][0] > 0 and stats['down'][0] > 0 and stats['dropped'] == 0
        inside = _in_namespaces(hosts, at_least=1)
        assert sleeper.pid in inside
    assert sleeper.poll() is not None and _alive(inside) == []
    assert namespaces(owner_pid=hosts_pid(hosts.tag)) == []


def hosts_pid(tag: str) -> int:
    return int(tag[3:])


# A process that makes hosts, starts a sleeper in one and waits (to be stopped by the test).
OWNER = (
    'import sys, time; from matrix_bringup.netns_harness import Hosts\n'
    'h = Hosts(["D1"]).__enter__(); p = h.start("D1", ["sleep", "600"], sys.argv[1]); '
    'print(h.tag, p.pid, flush=True); time.sleep(600)'
)


def test_teardown_on_failure_on_sigterm_and_after_the_owner_was_killed(tmp_path):
    with pytest.raises(RuntimeError, match='boom'):
        with Hosts(['D1']) as hosts:
            hosts.start(GROUND, ['sleep', '600'], tmp_path / 'a.log')
            inside = _in_namespaces(hosts, at_least=1)
            raise RuntimeError('boom')
    assert len(inside) == 1 and _alive(inside) == [] and namespaces(owner_pid=hosts_pid(hosts.tag)) == []

    # SIGTERM to the owner: it tears everything down before it exits
    owner = subprocess.Popen([sys.executable, '-c', OWNER, str(tmp_path / 'c.log')], stdout=subprocess.PIPE, text=True)
    tag, sleeper = owner.stdout.readline().split()
    owner.terminate()
    assert owner.wait(DEADLINE_S) == 128 + 15 and _alive([int(sleeper)]) == []
    assert namespaces(owner_pid=owner.pid) == []

    # An owner killed with SIGKILL cannot clean up: its processes get SIGTERM (they die with it) and the
    # next Hosts (or remove_stale) deletes its namespaces.
    owner = subprocess.Popen([sys.executable, '-c', OWNER, str(tmp_path / 'b.log')], stdout=subprocess.PIPE, text=True)
    tag, sleeper = owner.stdout.readline().split()
    assert sorted(namespaces(owner_pid=owner.pid)) == sorted([f'{tag}-ground', f'{tag}-D1'])
    owner.kill()
    owner.wait()
    _wait_for(lambda: _alive([int(sleeper)]) == [], 'the sleeper to die with its owner (PR_SET_PDEATHSIG)')
    assert sorted(remove_stale()) == sorted([f'{tag}-ground', f'{tag}-D1'])
    assert namespaces(owner_pid=owner.pid) == []
