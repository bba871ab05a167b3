"""QoS profiles chosen by name, so that a parameter can select them.

Convention of this workspace: every publisher offers ``publisher_qos`` (reliable streams are offered
*transient local*: a subscriber that asks for it also gets the last ``depth`` messages published before
it matched). Nodes that act on the present (calib, register, fuse) subscribe ``reliable`` (volatile: after
a restart they never process stale frames); observers that must not miss the start of a run (recorder,
graph monitor, the player's lockstep) subscribe ``history``. A volatile subscriber matches a transient-local
publisher; the reverse does not match (rclpy logs a warning naming the policy; nothing flows).
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

QOS_NAMES = ('sensor_data', 'reliable', 'history')


def qos_by_name(name: str, depth: int = 10) -> QoSProfile:
    """Subscription profiles: 'sensor_data' (best effort, small queue), 'reliable' (keep last ``depth``,
    volatile) or 'history' (the same, transient local: also the messages published before matching)."""
    if name == 'sensor_data':
        return qos_profile_sensor_data
    if name in ('reliable', 'history'):
        durability = DurabilityPolicy.TRANSIENT_LOCAL if name == 'history' else DurabilityPolicy.VOLATILE
        return QoSProfile(
            depth=depth, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST, durability=durability
        )
    raise ValueError(f'unknown QoS {name!r}; choose one of {QOS_NAMES}')


def publisher_qos(name: str = 'reliable', depth: int = 10) -> QoSProfile:
    """What this workspace's publishers offer: 'sensor_data' as is, reliable streams transient local
    (the writer keeps its last ``depth`` messages for retransmission anyway; late observers get them)."""
    return qos_profile_sensor_data if name == 'sensor_data' else qos_by_name('history', depth)
