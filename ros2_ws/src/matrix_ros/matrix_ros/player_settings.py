"""Parameters of the ``bag_player`` node (``matrix_ros.bag_player``)."""

from dataclasses import dataclass, field

from matrix_core.site.parameter import site_field
from matrix_ros.qos import qos_by_name


@dataclass
class BagPlayerSettings:
    bag: str = field(default='', metadata={'help': 'rosbag2 folder to play'})
    site: str = site_field()  # a bag naming drones the site lacks is refused before anything is played
    rate: float = field(default=1.0, metadata={'help': 'speed factor of the recorded timing (without lockstep)'})
    topics: list[str] = field(default_factory=list, metadata={'help': 'topics to play (empty = all)'})
    lockstep: bool = field(default=False, metadata={'help': 'wait for lockstep_topic before each next frame'})
    lockstep_topic: str = field(default='', metadata={'help': 'topic whose stamped messages release the next frame'})
    lockstep_type: str = field(
        default='', metadata={'help': 'message type of lockstep_topic, e.g. matrix_msgs/msg/TrackArray'}
    )
    lockstep_count: int = field(default=1, metadata={'help': 'messages per frame to wait for on lockstep_topic'})
    lockstep_timeout: float = field(default=30.0, metadata={'help': 'seconds to wait before going on anyway'})
    lockstep_window: int = field(
        default=1,
        metadata={
            'help': 'lockstep: frames out before the oldest of them must be released; 1: one frame at a time, 2: the '
            'next frame leaves while the last is finished (the drones register it while fuse fuses the last; '
            'every stage still gets every frame, in order)'
        },
    )
    lockstep_qos: str = field(
        default='history',
        metadata={
            'help': 'QoS of the lockstep subscription: history (also messages published before matching; needs a '
            'transient-local publisher, as all of this workspace\'s are) or reliable (any publisher)'
        },
    )
    wait_for_subscribers: int = field(
        default=0, metadata={'help': 'before the first frame, wait until every image topic has this many subscribers'}
    )
    start_at: float = field(
        default=0.0,
        metadata={
            'help': 'without lockstep: wall-clock time (Unix seconds) at which the first frame is due, frame k '
            'k periods later, so that the players of several hosts publish each frame together; frames '
            'due before the player is ready are skipped (0: start when ready)'
        },
    )
    start_topic: str = field(
        default='',
        metadata={
            'help': 'without lockstep: once ready (its subscribers matched), subscribe this topic and wait for one '
            'std_msgs/Header whose stamp is the start_at of the players of every host (published once they all '
            'are ready, so no player starts late: matrix_bringup.start_signal); empty: start_at as given'
        },
    )
    qos: str = field(default='reliable', metadata={'help': 'QoS of the published topics: reliable or sensor_data'})
    exit_when_done: bool = field(default=True, metadata={'help': 'exit after the last frame'})

    def __post_init__(self):
        if self.rate <= 0 or self.lockstep_timeout <= 0 or self.lockstep_count < 1 or self.lockstep_window < 1:
            raise ValueError('rate and lockstep_timeout must be positive, lockstep_count and lockstep_window >= 1')
        if self.lockstep and not (self.lockstep_topic and self.lockstep_type):
            raise ValueError('lockstep needs lockstep_topic and lockstep_type')
        qos_by_name(self.qos)
        qos_by_name(self.lockstep_qos)
