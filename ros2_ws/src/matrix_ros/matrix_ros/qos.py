"""QoS profiles chosen by name, so that a parameter can select them."""

from rclpy.qos import QoSProfile, ReliabilityPolicy, HistoryPolicy, qos_profile_sensor_data

QOS_NAMES = ('sensor_data', 'reliable')


def qos_by_name(name: str, depth: int = 10) -> QoSProfile:
    """'sensor_data' (best effort, small queue) or 'reliable' (keep last ``depth``)."""
    if name == 'sensor_data':
        return qos_profile_sensor_data
    if name == 'reliable':
        return QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE, history=HistoryPolicy.KEEP_LAST)
    raise ValueError(f'unknown QoS {name!r}; choose one of {QOS_NAMES}')
