"""``link_sender``: a drone's camera images across its link to the ground, a frame only once the link has had
time to carry the ones before it (``matrix_core.link_gate``), the others dropped whole at the sender.

Per drone (``views``, relative names as ``matrix_core.topics``; in a drone's namespace, as on a drone host,
the bare names of that drone): subscribes ``image_topic`` (CompressedImage from the camera, on the drone:
calib and register there read every frame themselves) and republishes each frame the gate lets through on
``link_topic``, best effort and volatile (``sensor_data``): nothing waits to be resent across the link (a lost
packet loses that frame; the next one comes a frame period later) and a reader that joins late gets no old
frame. The header of each frame dropped goes out on ``dropped_topic`` (std_msgs/Header, reliable: tiny),
so that the ground need not wait for that image (fuse's ``dropped_topic``). Per frame, a
``link_sender/<view>`` status on ``/diagnostics`` stamped with the frame's stamp: sent, or dropped and why,
with the counts so far. Used by ``matrix_bringup.deployment`` (one per drone host; fuse on the ground reads
``link_topic`` and ``dropped_topic``).
"""

import time
from dataclasses import dataclass, field

from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import CompressedImage
from std_msgs.msg import Header

from matrix_core import topics
from matrix_core.link_gate import DROPPED, LinkGate
from matrix_ros import diagnostics
from matrix_ros.node_settings import hosted_drones
from matrix_ros.params import SettingsNode, declare_settings, spin_node
from matrix_ros.qos import publisher_qos, qos_by_name


@dataclass
class LinkSenderSettings:
    views: list[str] = field(
        default_factory=list,
        metadata={'help': "drones whose images to send (empty: the drone of the node's namespace)"},
    )
    image_topic: str = field(
        default=topics.IMAGE_COMPRESSED, metadata={'help': "the camera's CompressedImage stream, relative to the drone"}
    )
    link_topic: str = field(
        default=topics.LINK_IMAGE_COMPRESSED,
        metadata={'help': 'the stream across the link, relative to the drone (what the ground reads)'},
    )
    dropped_topic: str = field(
        default=topics.LINK_DROPPED,
        metadata={'help': 'the headers of the frames not sent (std_msgs/Header), relative to the drone'},
    )
    link_mbit: float = field(
        default=0.0,
        metadata={
            'help': "Mbit/s of the drone's link the images may use (leave room for geometry, diagnostics and "
            'discovery); a frame leaves once the ones before it had time to cross; 0: every frame'
        },
    )

    def __post_init__(self):
        LinkGate(self.link_mbit)  # raises naming the setting
        if len({self.image_topic, self.link_topic, self.dropped_topic}) < 3:
            raise ValueError(
                'image_topic, link_topic and dropped_topic must differ, got '
                f'{self.image_topic!r}, {self.link_topic!r}, {self.dropped_topic!r}'
            )


class LinkSender(SettingsNode):
    def __init__(self, cli_settings: LinkSenderSettings = None):
        super().__init__('link_sender')
        self.settings = s = declare_settings(self, LinkSenderSettings, cli_settings)
        self.diagnostics = self.create_publisher(DiagnosticArray, topics.DIAGNOSTICS_TOPIC, publisher_qos())
        self.gates = {}
        for view, prefix in hosted_drones(self, s.views):
            self.gates[view] = LinkGate(s.link_mbit)
            pubs = (
                self.create_publisher(
                    CompressedImage, topics.drone_topic(prefix, s.link_topic), publisher_qos('sensor_data')
                ),
                self.create_publisher(Header, topics.drone_topic(prefix, s.dropped_topic), publisher_qos()),
            )
            self.create_subscription(
                CompressedImage,
                topics.drone_topic(prefix, s.image_topic),
                lambda msg, v=view, p=pubs: self._frame(v, *p, msg),
                qos_by_name('reliable', 2),
            )
        budget = f'{s.link_mbit:g} Mbit/s' if s.link_mbit else 'no budget: every frame'
        self.get_logger().info(f'sending {", ".join(self.gates)}: {s.image_topic} -> {s.link_topic}, {budget}')

    def _frame(self, view: str, pub, dropped_pub, msg: CompressedImage) -> None:
        gate, now = self.gates[view], time.monotonic()
        busy_s = gate.busy_s(now)
        outcome = gate.offer(now, len(msg.data))
        if outcome == DROPPED:
            dropped_pub.publish(msg.header)
            level = diagnostics.WARN
            why = f'dropped at the sender: the link carries the frames before for {busy_s:.2f} s'
        else:
            pub.publish(msg)
            level, why = diagnostics.OK, 'sent'
        c = gate.counts
        self.diagnostics.publish(
            diagnostics.array(
                msg.header.stamp,
                diagnostics.status(
                    f'link_sender/{view}',
                    level,
                    why,
                    {
                        'outcome': outcome,
                        'bytes': len(msg.data),
                        'sent': c.sent,
                        'dropped': c.dropped,
                        'link_busy_s': f'{busy_s:.3f}',
                    },
                    hardware_id=view,
                ),
            )
        )


def main(argv=None) -> int:
    return spin_node(LinkSender, LinkSenderSettings, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
