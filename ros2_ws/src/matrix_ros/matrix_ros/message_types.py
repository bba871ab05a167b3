"""ROS message classes from type names ('sensor_msgs/msg/Image'), for nodes that handle any topic."""

import importlib


def message_class(type_name: str):
    """'pkg/msg/Name' -> the rclpy message class; raises ValueError naming the type if unknown."""
    parts = type_name.split('/')
    if len(parts) != 3 or parts[1] != 'msg':
        raise ValueError(f'not a message type name: {type_name!r} (expected pkg/msg/Name)')
    try:
        return getattr(importlib.import_module(f'{parts[0]}.msg'), parts[2])
    except (ImportError, AttributeError) as exc:
        raise ValueError(f'message type {type_name} is not available in this environment') from exc
