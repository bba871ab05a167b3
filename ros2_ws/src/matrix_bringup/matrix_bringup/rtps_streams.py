"""What crosses a link, by DDS stream: Ethernet frames of RTPS over UDP/IPv4 sorted into the stream each
carries (a topic's data, its heartbeats or acknowledgements, participant or endpoint discovery), the topic
names learnt from the endpoint discovery (SEDP) crossing the same link. Pure Python, no capture here: see
:mod:`matrix_bringup.link_capture`, which feeds it the frames of a host's interface.

A frame is counted whole (Ethernet header included, as the link counters do) for the first submessage that
names an endpoint: DATA, DATA_FRAG, HEARTBEAT, GAP (the writer's stream) or ACKNACK, NACK_FRAG (the
reader's). The later IP fragments of a large datagram (an image is sent as ~64 kB datagrams, each ~45
frames on the wire) count for the stream of its first fragment; fragmented SEDP datagrams are reassembled
to learn every topic they name.
"""

import struct

# RTPS submessage ids (RTPS 2.3, 9.4.5)
ACKNACK, HEARTBEAT, GAP, NACK_FRAG, HEARTBEAT_FRAG, DATA, DATA_FRAG = 0x06, 0x07, 0x08, 0x12, 0x13, 0x15, 0x16
WRITER_SIDE = {
    DATA: 'data',
    DATA_FRAG: 'data',
    HEARTBEAT: 'heartbeats',
    HEARTBEAT_FRAG: 'heartbeats',
    GAP: 'heartbeats',
}
READER_SIDE = {ACKNACK: 'acknowledgements', NACK_FRAG: 'acknowledgements'}
# Builtin endpoints by entity id without its kind byte (RTPS 2.3, 9.3.1.2; Fast DDS's type lookup service)
BUILTIN = {
    b'\x00\x01\x00': 'discovery: participants (PDP)',
    b'\x00\x00\x03': 'discovery: endpoints (SEDP)',
    b'\x00\x00\x04': 'discovery: endpoints (SEDP)',
    b'\x00\x02\x00': 'liveliness (WLP)',
    b'\x00\x03\x00': 'type lookup',
    b'\x00\x03\x01': 'type lookup',
}
SEDP_WRITERS = (b'\x00\x00\x03\xc2', b'\x00\x00\x04\xc2')
PID_SENTINEL, PID_TOPIC_NAME, PID_ENDPOINT_GUID = 0x0001, 0x0005, 0x005A


def _parameters(buf: bytes, little: bool) -> dict:
    """A parameter list (pid -> value bytes) up to its sentinel or the end of ``buf`` (a cut datagram)."""
    out, pos, fmt = {}, 0, '<HH' if little else '>HH'
    while pos + 4 <= len(buf):
        pid, length = struct.unpack_from(fmt, buf, pos)
        if pid == PID_SENTINEL:
            break
        out[pid & 0x3FFF] = buf[pos + 4 : pos + 4 + length]
        pos += 4 + length
    return out


def _topic_name(value: bytes, little: bool) -> str:
    n = struct.unpack_from('<I' if little else '>I', value)[0]
    name = value[4 : 4 + n].rstrip(b'\0').decode('utf-8', 'replace')
    return name[2:] if name[:3] in ('rt/', 'rq/', 'rr/') else name  # ROS topics: 'rt/D1/image' -> '/D1/image'


class StreamCounter:
    """Bytes and frames per (direction, peer, stream, kind) over the frames given to :meth:`add`.

    ``peer``: the other end as named by ``hosts`` (address -> name; multicast: 'multicast'); ``stream``: a topic
    ('/D1/image/compressed', 'ros_discovery_info') or a builtin one ('discovery: participants (PDP)');
    ``kind``: 'data', 'heartbeats' or 'acknowledgements' ('' for builtins)."""

    def __init__(self, hosts: dict):
        self.hosts = hosts
        self.topics = {}  # endpoint GUID (16 bytes) -> topic, from the SEDP seen
        self.datagrams = {}  # (src, dst, IP id) -> key of its first fragment
        self.pieces = {}  # (src, dst, IP id) of a fragmented SEDP datagram -> {offset: bytes}
        self.totals = {}  # key -> [bytes, frames]

    def add(self, frame: bytes, outgoing: bool) -> None:
        key = self._key(frame, outgoing)
        count = self.totals.setdefault(key, [0, 0])
        count[0] += len(frame)
        count[1] += 1

    def table(self) -> list:
        """[{'direction', 'peer', 'stream', 'kind', 'bytes', 'frames'}], largest first."""
        rows = [
            dict(zip(('direction', 'peer', 'stream', 'kind'), k), bytes=v[0], frames=v[1])
            for k, v in self.totals.items()
        ]
        return sorted(rows, key=lambda r: -r['bytes'])

    def _key(self, frame: bytes, outgoing: bool) -> tuple:
        direction = 'up' if outgoing else 'down'
        if len(frame) < 34 or frame[12:14] != b'\x08\x00':
            return direction, '', 'other (not IPv4)', ''
        ip = frame[14:]
        header = (ip[0] & 0x0F) * 4
        src, dst = '.'.join(map(str, ip[12:16])), '.'.join(map(str, ip[16:20]))
        peer = dst if outgoing else src
        peer = 'multicast' if 224 <= int(dst.split('.')[0]) < 240 else self.hosts.get(peer, peer)
        flags_offset = struct.unpack_from('>H', ip, 6)[0]
        datagram, more = (src, dst, ip[4:6]), bool(flags_offset & 0x2000)
        if flags_offset & 0x1FFF:  # a later fragment: the stream of the first
            key = self.datagrams.get(datagram, (direction, peer, 'IP fragments of an unseen datagram', ''))
            if datagram in self.pieces:
                self._reassemble(datagram, (flags_offset & 0x1FFF) * 8, ip[header:], more)
            if not more:
                self.datagrams.pop(datagram, None)
            return key
        if ip[9] != 17:
            key = (direction, peer, 'other (not UDP)', '')
        else:
            stream, kind = self._rtps(ip[header + 8 :])
            key = (direction, peer, stream, kind)
        if more:  # more fragments follow
            if len(self.datagrams) > 10000:  # fragments lost for good: forget them
                self.datagrams.clear()
                self.pieces.clear()
            self.datagrams[datagram] = key
            if key[2].startswith('discovery: endpoints'):  # SEDP bundles many endpoints: learn from all
                self.pieces[datagram] = {0: ip[header:]}
        return key

    def _reassemble(self, datagram: tuple, offset: int, piece: bytes, more: bool) -> None:
        pieces = self.pieces[datagram]
        pieces[offset] = piece
        if not more:
            pieces['end'] = offset + len(piece)
        if 'end' in pieces and sum(len(v) for k, v in pieces.items() if k != 'end') == pieces['end']:
            del self.pieces[datagram]
            udp = b''.join(pieces[k] for k in sorted(k for k in pieces if k != 'end'))
            self._rtps(udp[8:])  # for the topics it names (the frames were counted already)

    def _rtps(self, msg: bytes) -> tuple:
        if msg[:4] != b'RTPS' or len(msg) < 20:
            return 'other (UDP, not RTPS)', ''
        prefix, pos, found = msg[8:20], 20, None
        while pos + 4 <= len(msg):
            sid, flags = msg[pos], msg[pos + 1]
            little = bool(flags & 1)
            size = struct.unpack_from('<H' if little else '>H', msg, pos + 2)[0]
            body = msg[pos + 4 : pos + 4 + size] if size else msg[pos + 4 :]
            if sid in WRITER_SIDE or sid in READER_SIDE:
                ids = body[4:12] if sid in (DATA, DATA_FRAG) else body[0:8]
                entity = ids[4:8] if sid in WRITER_SIDE else ids[0:4]
                if sid == DATA and entity in SEDP_WRITERS:  # every one of the message: learn the topics
                    self._learn(body, flags, little)
                found = found or (entity, WRITER_SIDE.get(sid) or READER_SIDE[sid])
            if not size:
                break
            pos += 4 + size
        if found is None:
            return 'RTPS without an endpoint (INFO only)', ''
        entity, kind = found
        if entity[3] & 0xC0 == 0xC0:  # builtin
            return BUILTIN.get(entity[:3], 'builtin ' + entity.hex()), ''
        return self.topics.get(prefix + entity, 'unknown endpoint'), kind

    def _learn(self, body: bytes, flags: int, little: bool) -> None:
        """From a SEDP DATA: endpoint GUID -> topic (its serialized payload is a parameter list)."""
        if not flags & 0x04 or len(body) < 4:  # no payload (a dispose)
            return
        start = 4 + struct.unpack_from('<H' if little else '>H', body, 2)[0]
        if flags & 0x02:  # inline QoS first
            inline = body[start:]
            pos = 0
            while pos + 4 <= len(inline):
                pid, length = struct.unpack_from('<HH' if little else '>HH', inline, pos)
                pos += 4 + length
                if pid == PID_SENTINEL:
                    break
            start += pos
        payload = body[start:]
        if len(payload) < 4:
            return
        payload_little = payload[1] in (0x01, 0x03)  # encapsulation PL_CDR_LE / CDR_LE
        params = _parameters(payload[4:], payload_little)
        if PID_TOPIC_NAME in params and len(params.get(PID_ENDPOINT_GUID, b'')) == 16:
            self.topics[params[PID_ENDPOINT_GUID]] = _topic_name(params[PID_TOPIC_NAME], payload_little)
