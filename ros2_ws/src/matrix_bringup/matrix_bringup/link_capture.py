"""``python -m matrix_bringup.link_capture --dev eth0 --hosts ground=10.213.0.1 ...``: the bytes crossing a
host's link by DDS stream (:class:`matrix_bringup.rtps_streams.StreamCounter`), from a raw packet socket on
``--dev`` (root; run inside the host's namespace). Frames are seen as they leave (after the link's limit:
what it dropped is not counted) and as they arrive. Prints, as JSON lines, the running totals every
``--every`` seconds (and once when it starts capturing, empty) and at SIGTERM: {"t": wall time, "streams":
StreamCounter.table()}.
"""

import argparse
import json
import select
import signal
import socket
import sys
import time

from matrix_bringup.rtps_streams import StreamCounter

ETH_P_ALL, PACKET_OUTGOING = 0x0003, 4


def _print(counter: StreamCounter) -> None:
    print(json.dumps({'t': round(time.time(), 3), 'streams': counter.table()}), flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--dev', default='eth0', help='the link interface')
    parser.add_argument('--hosts', nargs='*', default=[], help='NAME=ADDRESS: peers named in the output')
    parser.add_argument('--every', type=float, default=1.0, help='seconds between printed totals')
    args = parser.parse_args(argv)
    hosts = dict(reversed(h.split('=', 1)) for h in args.hosts)
    counter = StreamCounter(hosts)
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETH_P_ALL))
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)  # bursts of image fragments
    sock.bind((args.dev, 0))
    _print(counter)  # capturing: the first (empty) totals
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    next_print = time.monotonic() + args.every
    while not stop:
        if select.select([sock], [], [], 0.2)[0]:
            try:
                while True:  # drain: a burst of image fragments
                    frame, address = sock.recvfrom(65535, socket.MSG_DONTWAIT)
                    counter.add(frame, address[2] == PACKET_OUTGOING)
            except BlockingIOError:
                pass
        if time.monotonic() >= next_print:
            _print(counter)
            next_print += args.every
    _print(counter)
    return 0


if __name__ == '__main__':
    sys.exit(main())
