"""The wiring settings every processing node shares, validated once.

A node's settings dataclass is ``class XNodeSettings(NodeSettings, XSettings)``: NodeSettings first, so that
its ``__post_init__`` checks the wiring and then hands over to the core settings' own validation.
"""

from dataclasses import dataclass, field

import cv2

from matrix_ros.qos import QOS_NAMES, qos_by_name


@dataclass
class NodeSettings:
    qos: str = field(default='reliable', metadata={
        'help': f'QoS of the image subscriptions, one of {", ".join(QOS_NAMES)} (reliable: large images '
                'survive; sensor_data: best effort)'})
    threads: int = field(default=1, metadata={
        'help': 'OpenCV worker threads of this process (1: one core; idle pool threads of many processes on '
                'few cores cost CPU)'})

    def __post_init__(self):
        qos_by_name(self.qos)   # raises naming the valid names
        if self.threads < 1:
            raise ValueError(f'threads must be >= 1, got {self.threads}')
        if hasattr(super(), '__post_init__'):
            super().__post_init__()

    def apply_threads(self) -> None:
        """Limit OpenCV's worker pool of this process to ``threads``."""
        cv2.setNumThreads(self.threads)
