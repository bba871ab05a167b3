"""The wiring settings every processing node shares, validated once.

A node's settings dataclass is ``class XNodeSettings(NodeSettings, XSettings)``: the node's wiring and its
component's settings on one shared base (``matrix_core.settings.Settings``), each class checking its own fields.
Every processing node takes the ``site`` parameter here (``matrix_core.site.parameter.SiteSettings``).
"""

from dataclasses import dataclass, field

import cv2
from threadpoolctl import threadpool_limits

from matrix_core.site.parameter import SiteSettings
from matrix_core.threads import ThreadSettings
from matrix_ros.qos import QOS_NAMES, qos_by_name


@dataclass
class NodeSettings(SiteSettings, ThreadSettings):
    qos: str = field(
        default='reliable',
        metadata={
            'help': f'QoS of the image subscriptions, one of {", ".join(QOS_NAMES)} (reliable: large images '
            'survive; sensor_data: best effort)'
        },
    )

    def check(self) -> None:
        qos_by_name(self.qos)  # raises naming the valid names

    def apply_threads(self) -> None:
        """Limit OpenCV's and numpy's BLAS worker pools of this process to ``threads``.

        BLAS matters for the exact feature matcher's distance matrix: OpenBLAS threads spin while they wait,
        so two of them on a loaded 2-core machine cost about twice one's CPU time for the same product."""
        cv2.setNumThreads(self.threads)
        threadpool_limits(self.threads, user_api='blas')


def hosted_drones(node, views) -> list:
    """(view, topic prefix) of each drone a node serves (``matrix_core.topics``): each of ``views`` under its
    own name (``D3/image_raw``), except the drone whose namespace the node runs in (``/D3``: bare names,
    ``image_raw``); with ``views`` empty, that one drone (view = the namespace's last part, 'camera' in the
    root namespace)."""
    ns_view = node.get_namespace().strip('/').split('/')[-1]
    if not views:
        return [(ns_view or 'camera', '')]
    return [(view, '' if view == ns_view else view) for view in views]
