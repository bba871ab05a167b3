"""The graph deployed over hosts, as data: one computer per drone and a ground station, and what crosses each
drone's link, with the QoS of each stream and why. Built from the same :class:`~matrix_bringup.graph.GraphSettings`
and :func:`~matrix_bringup.graph.graph_nodes` as the one-host graph; pure Python (tested with plain pytest).

    drone host Dn:  bag_player (only Dn's camera: image/compressed, ground_truth/camera_info)
                    register, calib, link_sender (namespace /Dn: bare stream names)
         | link Dn: up   link/image/compressed (link_sender: the frames the link budget carries, best effort),
         |               link/dropped, homography, camera_info, pose, /diagnostics (reliable)
         |          down nothing but DDS discovery and acknowledgements
    ground host:    fuse, recorder, graph_monitor

Differences from the one-host graph, each for the link: images cross compressed only (a raw 1080p frame is
6.2 MB, 2.5 s at 20 Mbit/s), and not as the camera's stream but through ``link_sender``
(``matrix_core.link_gate``): on the drone, calib and register read every frame of the camera; across the
link a frame leaves only once the link budget (``link_mbit``) has carried the ones before, the others are
dropped whole at the sender, so a slow link neither queues old frames nor loses packets of every frame;
fuse reads that stream best effort (``qos: sensor_data``: nothing is resent across the link; a frame that
arrives after its stamp was fused is refused anyway) and link_sender's notices of the frames it dropped (it
need not wait for those images). The players run on the recorded timing (``lockstep``
off: a camera does not wait for the ground) and every host on its own clock (``use_sim_time`` off: no
``/clock`` across links; stamps are the bag's).
"""

from dataclasses import dataclass, replace

from matrix_bringup.graph import BagFacts, GraphSettings, NodeSpec, graph_nodes
from matrix_core import topics

GROUND = 'ground'
# fuse reads each drone's images from its link_sender, best effort, and its notices of frames not sent (STREAMS)
LINK_IMAGES = {
    'compressed_topic': '{view}/' + topics.LINK_IMAGE_COMPRESSED,
    'qos': 'sensor_data',
    'dropped_topic': '{view}/' + topics.LINK_DROPPED,
}
UP, DOWN = 'drone -> ground', 'ground -> drone'


@dataclass(frozen=True)
class LinkStream:
    """One stream across a drone's link: ``topic`` relative to the drone (``topics.drone_topic``) or absolute."""

    topic: str
    msg_type: str
    direction: str
    reliability: str  # 'best_effort' or 'reliable' (what the ground readers ask for)
    readers: tuple  # ground processes that subscribe it
    why: str


# Every per-drone stream a ground process may read: (stream, type, reliability, why).
STREAMS = {
    topics.LINK_IMAGE_COMPRESSED: (
        topics.COMPRESSED_TYPE,
        'best_effort',
        (
            "the camera's frames that link_sender lets through (a JPEG of 1080p, ~0.7 MB): a frame leaves once "
            'the link budget carried the ones before, the others are dropped whole at the sender (a slow link '
            'drops frames instead of queueing them or losing packets of each); best effort: nothing is resent, '
            'fuse wants the newest frame only'
        ),
    ),
    topics.LINK_DROPPED: (
        topics.HEADER_TYPE,
        'reliable',
        ('tiny; the stamp of each frame link_sender dropped: fuse fuses that frame without waiting for its image'),
    ),
    topics.HOMOGRAPHY: (
        topics.HOMOGRAPHY_TYPE,
        'reliable',
        ('tiny (~0.3 kB) and the geometry of its image: without it the view is missing for that frame'),
    ),
    topics.CAMERA_INFO: (topics.CAMERA_INFO_TYPE, 'reliable', 'tiny; the calibration of each frame'),
    topics.POSE: (topics.POSE_TYPE, 'reliable', 'tiny; recorded for evaluation'),
    topics.TF_TOPIC: (
        topics.TF_TYPE,
        'reliable',
        "tiny; calib's pose again as world -> Dn/camera_optical, for viewers (recorded, live view)",
    ),
    topics.GROUND_TRUTH_CAMERA_INFO: (topics.CAMERA_INFO_TYPE, 'reliable', 'tiny; only the monitor reads it'),
    topics.DIAGNOSTICS_TOPIC: (
        topics.DIAGNOSTIC_ARRAY_TYPE,
        'reliable',
        ("calib's and register's status per frame (~1 kB): why a view failed, recorded on the ground"),
    ),
}


@dataclass
class Deployment:
    """``hosts``: host name ('D1', ..., 'ground') -> its processes, in start order (the player last);
    ``links``: drone -> the streams crossing its link."""

    hosts: dict
    links: dict

    @property
    def drones(self) -> list:
        return [h for h in self.hosts if h != GROUND]

    def host_of(self, label: str) -> str:
        return next(h for h, nodes in self.hosts.items() if any(n.label == label for n in nodes))

    def describe(self) -> str:
        """The layout as text (docs/deployment.md, ``bench_distributed.py --layout``)."""
        lines = []
        for host, nodes in self.hosts.items():
            lines.append(f'{host}: ' + ', '.join(n.label for n in nodes))
        for drone, streams in self.links.items():
            for st in streams:
                lines.append(
                    f'  link {drone} {st.direction}: {st.topic} [{st.msg_type}] {st.reliability} '
                    f'-> {", ".join(st.readers)}: {st.why}'
                )
        return '\n'.join(lines)


def deployment(s: GraphSettings, bag: BagFacts = None, link_mbit=0.0) -> Deployment:
    """The graph of ``s`` on one host per drone plus the ground station (see the module docstring).
    ``link_mbit``: the image budget of each drone's link (``link_sender``; 0: every frame is sent), one
    for all or a dict by drone (drones not in it: 0)."""
    if s.drones_per_process != 1:
        raise ValueError('a deployment runs one drone per host: drones_per_process must be 1')
    bag = bag or BagFacts.read(s.bag, s.views, s.remap)
    if not bag.compressed:
        raise ValueError(
            'a deployment sends compressed images over the links, never raw 1080p: '
            'write the bag with compressed images (matrix-tracker bag ... --compressed)'
        )
    nodes = [_on_wall_clock(n) for n in graph_nodes(replace(s, lockstep=False), bag)]
    player = nodes.pop()
    hosts = {v: [n for n in nodes if n.namespace == v] for v in s.views}
    hosts[GROUND] = [n for n in nodes if n.namespace not in s.views]
    hosts[GROUND] = [
        replace(n, parameters={**n.parameters, **LINK_IMAGES}) if n.executable == 'fuse' else n for n in hosts[GROUND]
    ]
    for v in s.views:
        own = [topics.absolute(v, topics.IMAGE_COMPRESSED)]  # as its camera would: this drone's streams only
        if bag.has_ground_truth:
            own.append(topics.absolute(v, topics.GROUND_TRUTH_CAMERA_INFO))
        # the camera's readers are the drone process and link_sender: as many as the one-host graph's
        # (drone and fuse), so the player's wait_for_subscribers holds
        budget = link_mbit.get(v, 0.0) if isinstance(link_mbit, dict) else link_mbit
        hosts[v] += [
            NodeSpec('matrix_ros', 'link_sender', 'link_sender', v, {'link_mbit': float(budget)}),
            NodeSpec(player.package, player.executable, player.name, v, {**player.parameters, 'topics': own}),
        ]
    return Deployment(hosts, {v: _link_streams(v, hosts[GROUND]) for v in s.views})


def _on_wall_clock(node: NodeSpec) -> NodeSpec:
    return (
        replace(node, parameters={**node.parameters, 'use_sim_time': False})
        if 'use_sim_time' in node.parameters
        else node
    )


def ground_reads(node: NodeSpec, view: str) -> list:
    """The per-drone streams (``STREAMS`` keys) a ground process subscribes for ``view``."""
    p = node.parameters
    if node.executable == 'fuse':
        geometry = topics.HOMOGRAPHY if p.get('input_kind') == 'homography' else topics.CAMERA_INFO
        image = p.get('compressed_topic', '{view}/' + topics.IMAGE_COMPRESSED).partition('/')[2]
        dropped = [p['dropped_topic'].partition('/')[2]] if p.get('dropped_topic') else []
        return [image, *dropped, geometry]
    if node.executable == 'recorder':
        recorded = set(p.get('topics', ()))
        return [st for st in STREAMS if topics.absolute(view, st) in recorded or st in recorded]
    if node.executable == 'live_view':
        return [topics.CAMERA_INFO, topics.TF_TOPIC]
    if node.executable == 'graph_monitor':
        return [topics.GROUND_TRUTH_CAMERA_INFO, topics.CAMERA_INFO, topics.HOMOGRAPHY, topics.DIAGNOSTICS_TOPIC]
    return []


def _link_streams(view: str, ground: list) -> list:
    readers = {}
    for node in ground:
        for st in ground_reads(node, view):
            readers.setdefault(st, []).append(node.label)
    return [
        LinkStream(
            st if st.startswith('/') else topics.drone_topic(view, st),
            STREAMS[st][0],
            UP,
            STREAMS[st][1],
            tuple(readers[st]),
            STREAMS[st][2],
        )
        for st in STREAMS
        if st in readers
    ]
