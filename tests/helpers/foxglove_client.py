"""A client of the Foxglove WebSocket protocol (``websockets``), as Foxglove or Lichtblick would connect: it reads
the server's info and channel list, subscribes, and decodes each binary message with the protobuf schema the
server advertised for its channel (a FileDescriptorSet, base64). Runs its own event loop in a thread, so that
a test can drive a ROS graph meanwhile.

Protocol (foxglove.sdk.v1 / foxglove.websocket.v1): text frames are JSON (``serverInfo``, ``advertise``, ...),
a message is a binary frame ``0x01 | subscription id (u32 LE) | log time (u64 LE ns) | payload``.
"""

import asyncio
import base64
import json
import struct
import threading
import time

import websockets
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

SUBPROTOCOLS = ['foxglove.sdk.v1', 'foxglove.websocket.v1']
MESSAGE_DATA = 0x01


def decoder(channel: dict):
    """The protobuf message class of an advertised channel (``encoding`` protobuf)."""
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel['schema']))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:  # dependencies come before the files that import them
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel['schemaName']))


async def wait_for_server(url: str, timeout_s: float):
    """An open connection to ``url`` once it accepts one (the node may still be starting)."""
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return await websockets.connect(url, subprotocols=SUBPROTOCOLS, max_size=None)
        except OSError:
            if time.monotonic() > deadline:
                raise
            await asyncio.sleep(0.2)


class FoxgloveClient:
    """Connects to ``url``, subscribes every channel whose topic ``wanted(topic)`` accepts, and keeps per topic
    the decoded messages (at most ``keep`` each) and their count, until :meth:`close`."""

    def __init__(self, url: str, wanted=lambda topic: True, keep: int = 3, timeout_s: float = 60.0):
        self.url, self.wanted, self.keep, self.timeout_s = url, wanted, keep, timeout_s
        self.info, self.channels, self.messages, self.counts, self.errors = None, {}, {}, {}, []
        self.connected = threading.Event()
        self._stop = asyncio.Event()
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_until_complete, args=(self._run(),), daemon=True)
        self._thread.start()

    async def _run(self):
        try:
            ws = await wait_for_server(self.url, self.timeout_s)
        except OSError as exc:
            self.errors.append(f'no connection: {exc}')
            self.connected.set()
            return
        self.ws = ws
        subscriptions, decoders = {}, {}
        async with ws:
            self.connected.set()
            receiving = asyncio.ensure_future(ws.recv())
            stopping = asyncio.ensure_future(self._stop.wait())
            while True:
                done, _ = await asyncio.wait({receiving, stopping}, return_when=asyncio.FIRST_COMPLETED)
                if stopping in done:
                    receiving.cancel()
                    return
                try:
                    frame = receiving.result()
                except websockets.ConnectionClosed as exc:
                    self.errors.append(f'closed: {exc}')
                    stopping.cancel()
                    return
                receiving = asyncio.ensure_future(ws.recv())
                if isinstance(frame, str):
                    msg = json.loads(frame)
                    if msg['op'] == 'serverInfo':
                        self.info = msg
                    elif msg['op'] == 'advertise':
                        new = []
                        for channel in msg['channels']:
                            self.channels[channel['topic']] = channel
                            if self.wanted(channel['topic']):
                                sub = len(subscriptions) + 1
                                subscriptions[sub], decoders[sub] = channel['topic'], decoder(channel)
                                new.append({'id': sub, 'channelId': channel['id']})
                        if new:
                            await ws.send(json.dumps({'op': 'subscribe', 'subscriptions': new}))
                    continue
                if frame[0] != MESSAGE_DATA:
                    continue
                sub, log_time = struct.unpack_from('<IQ', frame, 1)
                topic = subscriptions[sub]
                self.counts[topic] = self.counts.get(topic, 0) + 1
                kept = self.messages.setdefault(topic, [])
                kept.append((log_time, decoders[sub].FromString(frame[13:])))
                del kept[: -self.keep]

    def send(self, data) -> None:
        """Send a raw frame (text or bytes) to the server, as a broken client might."""
        asyncio.run_coroutine_threadsafe(self.ws.send(data), self._loop).result(10)

    def abort(self) -> None:
        """Drop the TCP connection without a closing handshake (a client that crashed or lost its network)."""
        self._loop.call_soon_threadsafe(self.ws.transport.abort)
        self._thread.join(10)

    def wait_for(self, topics, timeout_s: float) -> bool:
        """Whether every one of ``topics`` delivered a message within ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if all(self.counts.get(t) for t in topics):
                return True
            time.sleep(0.1)
        return False

    def close(self) -> None:
        if self._thread.is_alive():
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(10)
