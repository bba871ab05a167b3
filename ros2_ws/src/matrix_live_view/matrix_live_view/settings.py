"""Parameters of the ``live_view`` node: the scene (``matrix_core.live_scene``) plus the server and wiring."""

from dataclasses import dataclass, field

from matrix_core import topics
from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS
from matrix_core.live_scene import LiveSceneSettings


@dataclass
class LiveViewSettings(LiveSceneSettings):
    views: list[str] = field(
        default_factory=lambda: list(MATRIX_VIEWS), metadata={'help': 'drones whose cameras and overlays are shown'}
    )
    host: str = field(
        default='127.0.0.1',
        metadata={'help': 'address the WebSocket server listens on (0.0.0.0: every interface, for other machines)'},
    )
    port: int = field(default=topics.LIVE_VIEW_PORT, metadata={'help': 'its port (ws://HOST:PORT); 0 = any free one'})
    client_backlog: int = field(
        default=32,
        metadata={
            'help': 'messages queued per client at most: a slow client loses the oldest (about 20 a frame with 8 '
            'drones), the graph never waits for it'
        },
    )
    scene_dataset: str = field(
        default='',
        metadata={
            'help': "MATRIX folder of the scene: a simulated folder's meta gives the obstacles; '' = obstacle_boxes"
        },
    )

    def __post_init__(self):
        if not 0 <= self.port <= 65535 or self.client_backlog < 1:
            raise ValueError(
                f'port must be in [0, 65535] and client_backlog >= 1, got {self.port}, {self.client_backlog}'
            )
        super().__post_init__()
