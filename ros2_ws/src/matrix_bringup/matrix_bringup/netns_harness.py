"""Hosts as Linux network namespaces on one machine: a drone host per drone and a ground station, joined by
per-drone links that can be rate-limited (``tc tbf``) and cut (``ip link set down``), to run the deployment of
:mod:`matrix_bringup.deployment` over real (virtual) network links. Pure Python (``ip`` and ``tc``), root only.

Layout (all inside the namespaces; nothing is added to the machine's own network)::

    <ns>-ground:  br0 10.213.0.1/24 --+-- gw-D1 ==veth== eth0 10.213.0.11/24  :<ns>-D1
                                      +-- gw-D2 ==veth== eth0 10.213.0.12/24  :<ns>-D2 ...

The ground namespace holds the bridge and the ground end of every drone's veth pair, so deleting the
namespaces removes every link. Each host's link is limited on both ends (egress of the drone: the uplink
of its images; egress of the ground: the downlink). Processes started with :meth:`Hosts.start` run in their
host's namespace (``ip netns exec``), get SIGTERM if this process dies (PR_SET_PDEATHSIG), and are stopped
(SIGTERM, then SIGKILL) before the namespaces go. Teardown runs on leaving the ``with`` block, on exit
(``atexit``) and on SIGTERM; a namespace left by a process that died hard (SIGKILL) is removed by the next
:class:`Hosts` (its name carries its owner's pid). :func:`unavailable` says why namespaces cannot be made.

    with Hosts(['D1', 'D2'], rate_mbit=20) as hosts:
        hosts.start('D1', ['register', ...], log='D1_register.log')
        hosts.cut('D2'); ...; hosts.restore('D2')
"""

import atexit
import json
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

GROUND = 'ground'
SUBNET = '10.213.0'  # private /24 of the harness (only inside its namespaces)
_PREFIX = 'mxh'  # namespace names: mxh<pid>-<host>
_NAME = re.compile(rf'^{_PREFIX}(\d+)-')


def address(host: str, index: int = 0) -> str:
    """The host's address: ground .1, the drone at ``index`` (0-based) .11, .12, ..."""
    return f'{SUBNET}.1' if host == GROUND else f'{SUBNET}.{11 + index}'


def _ip(*args, check=True) -> subprocess.CompletedProcess:
    return subprocess.run(['ip', *args], capture_output=True, text=True, check=check)


def unavailable() -> str:
    """'' when network namespaces can be created here, else why not (for a test's skip reason)."""
    probe = f'{_PREFIX}{os.getpid()}-probe'
    try:
        made = _ip('netns', 'add', probe, check=False)
    except FileNotFoundError:
        return 'the `ip` command (iproute2) is not installed'
    if made.returncode:
        return f'cannot create network namespaces (needs root / CAP_SYS_ADMIN): {made.stderr.strip()}'
    _ip('netns', 'delete', probe, check=False)
    if subprocess.run(['tc', '-V'], capture_output=True).returncode:
        return 'the `tc` command is missing'
    return ''


def namespaces(owner_pid: int = None) -> list:
    """Names of the harness namespaces present (of ``owner_pid`` only, if given)."""
    names = [line.split()[0] for line in _ip('netns', 'list').stdout.splitlines() if line.strip()]
    return [n for n in names if (m := _NAME.match(n)) and (owner_pid is None or int(m.group(1)) == owner_pid)]


def remove_stale() -> list:
    """Delete harness namespaces whose owner process no longer runs (left by a SIGKILL); returns them."""
    stale = [n for n in namespaces() if not Path(f'/proc/{_NAME.match(n).group(1)}').exists()]
    for name in stale:
        _kill_pids(_ns_pids(name))
        _ip('netns', 'delete', name, check=False)
    return stale


def _ns_pids(ns: str) -> list:
    run = _ip('netns', 'pids', ns, check=False)
    return [int(p) for p in run.stdout.split()] if run.returncode == 0 else []


def _kill_pids(pids) -> None:
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def _die_with_parent():  # in the child between fork and exec: SIGTERM when the harness process dies
    import ctypes

    ctypes.CDLL('libc.so.6', use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


class Hosts:
    """The namespaces, links and processes of one run; a context manager (see the module docstring).

    ``drones``: host names ('D1', ...); ``rate_mbit``: tbf limit of every link (None: unlimited);
    ``multicast``: False adds no multicast route and clears the MULTICAST flag of every interface (as on a
    link that does not carry multicast; the kernel still sends multicast on a veth without the flag, so a
    test of unicast discovery also checks that nothing listens on the multicast port: :meth:`udp_ports`).
    """

    def __init__(self, drones, rate_mbit: float = None, multicast: bool = True):
        self.drones, self.rate_mbit, self.multicast = list(drones), rate_mbit, multicast
        self.tag = f'{_PREFIX}{os.getpid()}'
        self.procs = []  # (host, Popen)
        self._up = False

    def ns(self, host: str) -> str:
        return f'{self.tag}-{host}'

    @property
    def hosts(self) -> list:
        return [GROUND, *self.drones]

    def address(self, host: str) -> str:
        return address(host, self.drones.index(host) if host != GROUND else 0)

    def __enter__(self) -> 'Hosts':
        reason = unavailable()
        if reason:
            raise RuntimeError(reason)
        remove_stale()
        atexit.register(self.close)
        self._sigterm = signal.getsignal(signal.SIGTERM)
        if self._sigterm in (signal.SIG_DFL, None) and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, self._on_sigterm)
        self._up = True
        try:
            self._build()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _on_sigterm(self, signum, frame):
        self.close()
        raise SystemExit(128 + signum)

    def _build(self) -> None:
        ground = self.ns(GROUND)
        for host in self.hosts:
            _ip('netns', 'add', self.ns(host))
            _ip('-n', self.ns(host), 'link', 'set', 'lo', 'up')
        _ip('-n', ground, 'link', 'add', 'br0', 'type', 'bridge')
        _ip('-n', ground, 'addr', 'add', f'{self.address(GROUND)}/24', 'dev', 'br0')
        _ip('-n', ground, 'link', 'set', 'br0', 'up')
        self._route(GROUND, 'br0')
        for drone in self.drones:
            gw = self.ground_end(drone)
            _ip('-n', ground, 'link', 'add', gw, 'type', 'veth', 'peer', 'name', 'eth0', 'netns', self.ns(drone))
            _ip('-n', ground, 'link', 'set', gw, 'master', 'br0')
            _ip('-n', ground, 'link', 'set', gw, 'up')
            _ip('-n', self.ns(drone), 'addr', 'add', f'{self.address(drone)}/24', 'dev', 'eth0')
            _ip('-n', self.ns(drone), 'link', 'set', 'eth0', 'up')
            self._route(drone, 'eth0')
            if self.rate_mbit:
                self.limit(drone, self.rate_mbit)

    def _route(self, host: str, dev: str) -> None:
        """Multicast (DDS discovery) leaves by the host's only link; or, without multicast, the flag is off."""
        if self.multicast:
            _ip('-n', self.ns(host), 'route', 'add', '224.0.0.0/4', 'dev', dev)
        else:
            _ip('-n', self.ns(host), 'link', 'set', dev, 'multicast', 'off')

    @staticmethod
    def ground_end(drone: str) -> str:
        return f'gw-{drone}'

    def limit(self, drone: str, rate_mbit: float, burst_kb: int = 64, queue_kb: int = 1024) -> None:
        """Token-bucket limit of the drone's link, both directions: ``rate_mbit`` Mbit/s, a ``burst_kb`` bucket
        and a queue of ``queue_kb`` (a radio modem's buffer: one 1080p JPEG of ~0.7 MB and some); what does not
        fit in the queue is dropped at the sender's end."""
        args = ['root', 'tbf', 'rate', f'{rate_mbit}mbit', 'burst', f'{burst_kb}kb', 'limit', f'{queue_kb}kb']
        for ns, dev in ((self.ns(drone), 'eth0'), (self.ns(GROUND), self.ground_end(drone))):
            subprocess.run(
                ['ip', 'netns', 'exec', ns, 'tc', 'qdisc', 'replace', 'dev', dev, *args],
                check=True,
                capture_output=True,
                text=True,
            )

    def cut(self, drone: str) -> None:
        """The drone's link goes down (nothing passes either way) until :meth:`restore`."""
        _ip('-n', self.ns(GROUND), 'link', 'set', self.ground_end(drone), 'down')

    def restore(self, drone: str) -> None:
        _ip('-n', self.ns(GROUND), 'link', 'set', self.ground_end(drone), 'up')

    def link_bytes(self, drone: str) -> dict:
        """Bytes and packets that crossed the drone's link so far: {'up': (bytes, packets), 'down': ...,
        'dropped': packets the limit dropped at the drone's end}."""
        stats = json.loads(_ip('-n', self.ns(drone), '-s', '-j', 'link', 'show', 'dev', 'eth0').stdout)[0]['stats64']
        qdisc = subprocess.run(
            ['ip', 'netns', 'exec', self.ns(drone), 'tc', '-s', '-j', 'qdisc', 'show', 'dev', 'eth0'],
            capture_output=True,
            text=True,
        ).stdout
        dropped = sum(q.get('drops', 0) for q in json.loads(qdisc or '[]'))
        return {
            'up': (stats['tx']['bytes'], stats['tx']['packets']),
            'down': (stats['rx']['bytes'], stats['rx']['packets']),
            'dropped': dropped,
        }

    def udp_ports(self, host: str) -> set:
        """Local UDP ports bound in the host (``ss``)."""
        out = subprocess.run(
            ['ip', 'netns', 'exec', self.ns(host), 'ss', '-uanH'], capture_output=True, text=True, check=True
        ).stdout
        return {int(line.split()[3].rsplit(':', 1)[1]) for line in out.splitlines() if line.strip()}

    def udp_errors(self, host: str) -> dict:
        """The host's UDP counters of datagrams lost on receipt (/proc/net/snmp of its namespace):
        {'RcvbufErrors': n (socket buffer full), 'InErrors': n, ...}."""
        text = subprocess.run(
            ['ip', 'netns', 'exec', self.ns(host), 'cat', '/proc/net/snmp'], capture_output=True, text=True, check=True
        ).stdout
        names, values = [line.split()[1:] for line in text.splitlines() if line.startswith('Udp:')][:2]
        return {k: int(v) for k, v in zip(names, values) if 'Err' in k}

    def start(self, host: str, cmd, log: Path, env: dict = None) -> subprocess.Popen:
        """Run ``cmd`` in ``host``'s namespace, stdout and stderr to the file ``log`` (its first line: cmd)."""
        log = Path(log)
        log.parent.mkdir(parents=True, exist_ok=True)
        with open(log, 'w') as out:
            out.write(' '.join(map(str, cmd)) + '\n')
            out.flush()
            proc = subprocess.Popen(
                ['ip', 'netns', 'exec', self.ns(host), *map(str, cmd)],
                stdout=out,
                stderr=subprocess.STDOUT,
                env=env,
                preexec_fn=_die_with_parent,
            )
        self.procs.append((host, proc))
        return proc

    def stop(self, proc: subprocess.Popen, timeout: float = 10.0) -> int:
        """SIGTERM, SIGKILL after ``timeout`` s; returns the exit code."""
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            return proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            return proc.wait()

    def stop_all(self, timeout: float = 10.0) -> None:
        for _, proc in self.procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + timeout
        for _, proc in self.procs:
            try:
                proc.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()

    def close(self) -> None:
        """Stop every process, kill any other left in the namespaces, delete the namespaces (idempotent)."""
        if not self._up:
            return
        self._up = False
        try:
            self.stop_all()
        finally:
            for host in self.hosts:
                _kill_pids(_ns_pids(self.ns(host)))
            for host in reversed(self.hosts):  # drones first; the ground's deletion removes the bridge
                _ip('netns', 'delete', self.ns(host), check=False)
            atexit.unregister(self.close)
            if signal.getsignal(signal.SIGTERM) == self._on_sigterm:
                signal.signal(signal.SIGTERM, self._sigterm)
