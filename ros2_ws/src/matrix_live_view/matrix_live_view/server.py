"""The live view's Foxglove WebSocket server (foxglove-sdk): its channels, and its own log lines in the node's log.

The SDK's server runs on threads of its own; ``log`` hands a message over and returns. Each client has an
outbox of ``backlog`` messages: when a slow client's fills, the SDK drops the oldest message for it
("outbox ... full"), so nothing queues and the node never waits. Its log lines (a client registered, closed
or reset, an invalid message and why) go to the node's logger, with the client's address.
"""

import logging

import foxglove
from foxglove import channels

# Foxglove schema -> its channel class
CHANNELS = {
    'scene': channels.SceneUpdateChannel,
    'grid': channels.GridChannel,
    'image': channels.CompressedImageChannel,
    'calibration': channels.CameraCalibrationChannel,
    'transforms': channels.FrameTransformsChannel,
}


class _ToRosLog(logging.Handler):
    """Python logging records (the SDK's) -> the node's logger, at the same level."""

    def __init__(self, logger):
        super().__init__(logging.INFO)
        self.logger = logger

    def emit(self, record):
        text = f'foxglove: {record.getMessage()}'
        if record.levelno >= logging.ERROR:
            self.logger.error(text)
        elif record.levelno >= logging.WARNING:
            self.logger.warning(text)
        else:
            self.logger.info(text)


class _Listener:
    """What clients ask for, logged (a disconnect unsubscribes every channel of that client)."""

    def __init__(self, logger):
        self.logger = logger

    def on_subscribe(self, client, channel) -> None:
        self.logger.info(f'client {client.id} subscribed {channel.topic}')

    def on_unsubscribe(self, client, channel) -> None:
        self.logger.info(f'client {client.id} unsubscribed {channel.topic} (or left)')


class LiveServer:
    """A server on ``host``:``port`` (0: any free port, see :attr:`port`) with channels made on first use."""

    def __init__(self, logger, host: str, port: int, backlog: int, name: str = 'matrix-tracker live view'):
        sdk_log = logging.getLogger('foxglove')
        sdk_log.addHandler(_ToRosLog(logger))
        sdk_log.propagate = False  # not also on the root logger's handlers
        foxglove.set_log_level('INFO')  # the SDK forwards its (Rust) log to Python logging from here on
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(
                name=name,
                host=host,
                port=port,
                context=self.context,
                server_listener=_Listener(logger),
                message_backlog_size=backlog,
            )
        except RuntimeError as exc:  # the SDK's FoxgloveError, e.g. the port is taken
            raise RuntimeError(f'live view: cannot serve on {host}:{port} ({exc}); choose another port') from exc
        self.channels = {}

    @property
    def port(self) -> int:
        return self.server.port

    def channel(self, kind: str, topic: str):
        """The channel of ``topic`` for messages of ``kind`` (a key of :data:`CHANNELS`)."""
        if topic not in self.channels:
            self.channels[topic] = CHANNELS[kind](topic, context=self.context)
        return self.channels[topic]

    def wanted(self, kind: str, topic: str) -> bool:
        """Whether any client subscribed ``topic``: messages nobody receives are not even built."""
        return self.channel(kind, topic).has_sinks()

    def log(self, kind: str, topic: str, message) -> None:
        self.channel(kind, topic).log(message)

    def stop(self) -> None:
        self.server.stop()
