"""The live graph as data: which nodes run, with which parameters, to replay one sequence bag.

Both ways of starting the graph build their processes from :func:`graph_nodes`: ``launch/full_graph.launch.py``
(``ros2 launch``: a ROS 2 install's, or the one ``make setup`` builds here), and ``run_graph`` where there is
no ``ros2 launch``, which starts the same executables from ``install/``. Pure Python (no rclpy, no launch),
so the graph itself is tested with plain pytest.

    bag_player --images--> register (per drone) --homography--> fuse --tracks--> recorder, [graph_monitor]
               --images--> calib (per drone) <--homography--+ (calib_registration)
               --images--> fuse       calib --camera_info, pose--> recorder, [graph_monitor]

With one drone per process the calib and register processes run in namespace /Dn; their topics are the
absolute /Dn/... either way. With ``drone_process`` (the default) a drone's calib and register are one process
(``drone``: matrix_bringup.drone), the image subscribed and decoded once and the registration handed over in
process; same nodes, topics and parameters.

Lockstep: the player releases the next frame when the fuse node published tracks for the last one, or,
with ``monitor``, when the monitor saw every stage (calib, register and tracks) finish it, so that no node
falls behind the replay. The drone processes start niced (``drone_niceness``): on one computer fuse, the
last stage, finishes a frame before the next frame's registrations take the cores.
"""

import logging
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from matrix_core import topics
from matrix_core.bags.salvage import topic_counts
from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS
from matrix_core.settings import setting_to_string
from matrix_core.site import matrix_site
from matrix_core.site.parameter import check_drones, named_site, recorded_drones, site_field

_log = logging.getLogger(__name__)

VIEWS = list(MATRIX_VIEWS)
RECORDED = (
    *map(topics.graph_topic, (topics.TRACKS, topics.DETECTIONS, topics.BEV_HEATMAP)),
    topics.DIAGNOSTICS_TOPIC,
    topics.TF_TOPIC,  # the cameras: a recording opens in a viewer with them placed
    topics.TF_STATIC_TOPIC,
)
PER_VIEW_RECORDED = (topics.CAMERA_INFO, topics.POSE, topics.HOMOGRAPHY, topics.DETECTIONS_2D)
OVERLAY_RECORDED = topics.OVERLAY_COMPRESSED  # with GraphSettings.overlay
DRONE_NODES = ('calib', 'register')  # the nodes of a drone process (matrix_bringup.drone)


@dataclass
class GraphSettings:
    """Launch arguments of ``full_graph.launch.py`` and flags of ``run_graph`` (same names and defaults)."""

    bag: str = field(
        default='',
        metadata={
            'help': 'sequence bag to replay (matrix-tracker bag DATASET --out BAG, or matrix-tracker simulate --bag)'
        },
    )
    dataset: str = field(
        default='',
        metadata={
            'help': "the dataset folder the bag came from (MATRIX format or a site dataset): its reference images and "
            "calibrations are register's references and calib's first prior; empty: the site file's references "
            '(a site with references: site init, a site dataset\'s site.yaml)'
        },
    )
    site: str = site_field()
    remap: list[str] = field(
        default_factory=list,
        metadata={
            'help': "the bag's topics renamed to the graph's, ROS remapping rules FROM:=TO of absolute names, e.g. "
            '/cam_front/image:=/alpha/image_raw (the player publishes FROM on TO)'
        },
    )
    views: list[str] = field(
        default_factory=lambda: list(VIEWS), metadata={'help': "drones to run; default: the site's drones"}
    )
    drones_per_process: int = field(
        default=1,
        metadata={
            'help': 'drones per calib and per register process: 1 = one process each per drone, in namespace /Dn '
            '(as on one computer per drone); N > 1: processes calib_1, calib_2, ... with N drones each; '
            '0 = one process each for all drones'
        },
    )
    drone_process: bool = field(
        default=True,
        metadata={
            'help': "a drone's calib and register nodes in one process (drone): each image subscribed and decoded "
            'once, its registration handed to calib in process; false: a calib and a register process'
        },
    )
    calib_config: str = field(
        default='',
        metadata={
            'help': "calibration scene YAML (boards, intrinsics); empty: the shipped one for the dataset "
            "(sim_<variant>.yaml for a simulated folder, else matrix_sample.yaml)"
        },
    )
    calib_registration: bool = field(
        default=True,
        metadata={
            'help': "calib follows each drone's registration (use_registration: the camera the registration implies "
            'predicts the boards, about 5x less calib time); false: calib measures the image motion itself'
        },
    )
    register_params: str = field(
        default='', metadata={'help': 'ROS parameter file of register; empty: matrix_register/config/register.yaml'}
    )
    fuse_params: str = field(
        default='', metadata={'help': 'ROS parameter file of fuse; empty: matrix_bev_tracker/config/fuse.yaml'}
    )
    input_kind: str = field(
        default='homography',
        metadata={'help': "fuse on register's homographies (homography) or on calib's camera_info (camera_info)"},
    )
    checkpoint: str = field(default='', metadata={'help': 'BEV checkpoint (.pt); empty: the fuse node default'})
    overlay: bool = field(
        default=False,
        metadata={
            'help': "fuse also publishes (and the recorder records) each drone's image with the tracks' boxes and ids "
            'drawn (Dn/overlay/compressed)'
        },
    )
    live_view: bool = field(
        default=False,
        metadata={
            'help': 'also run live_view (matrix_live_view): the graph over the Foxglove WebSocket protocol on '
            "ws://localhost:live_view_port for Foxglove or Lichtblick; fuse then publishes the drones' overlays"
        },
    )
    live_view_port: int = field(default=topics.LIVE_VIEW_PORT, metadata={'help': "the live view's port"})
    sync_timeout: float = field(
        default=5.0,
        metadata={
            'help': 'seconds the fuse node waits for a late drone before fusing without it (without lockstep; '
            'in lockstep it waits lockstep_timeout, so that every view is fused)'
        },
    )
    lockstep: bool = field(
        default=True,
        metadata={
            'help': 'true: the next frame leaves the bag once the last one is processed (deterministic); '
            'false: the recorded timing scaled by rate'
        },
    )
    lockstep_timeout: float = field(
        default=120.0,
        metadata={'help': 'seconds the player waits for a frame to be processed before going on (logged)'},
    )
    lockstep_window: int = field(
        default=2,
        metadata={
            'help': 'lockstep: frames out at once; 2: the next frame leaves while fuse finishes the last (the drones '
            'register it meanwhile: faster, the same results), 1: one frame through the whole graph at a time'
        },
    )
    rate: float = field(default=1.0, metadata={'help': 'replay speed without lockstep'})
    record: str = field(
        default='',
        metadata={
            'help': 'bag folder the recorder creates (must not exist; tracks as MOT text beside it); empty: no recorder'
        },
    )
    monitor: bool = field(
        default=False,
        metadata={
            'help': "also run graph_monitor: scores calib and register against the bag's ground truth and paces "
            'lockstep on every stage (needs ground_truth/camera_info in the bag)'
        },
    )
    monitor_out: str = field(default='out/graph_monitor', metadata={'help': "graph_monitor's table and picture"})
    drone_niceness: int = field(
        default=10,
        metadata={
            'help': 'niceness (0-19) of the drone processes (calib, register): on one computer a frame in fuse is '
            "not held up by the next frame's registrations, which wait instead (the latency at 2 Hz); "
            '0 = the same priority as fuse'
        },
    )
    dds_profile: str = field(
        default='',
        metadata={
            'help': 'Fast DDS profile XML for every node, e.g. share/matrix_bringup/config/fastdds.xml (large images '
            "in shared memory, 0.1 s heartbeat); empty: the environment's FASTRTPS_DEFAULT_PROFILES_FILE"
        },
    )

    def __post_init__(self):
        if self.input_kind not in ('homography', 'camera_info'):
            raise ValueError(f'input_kind must be homography or camera_info, got {self.input_kind!r}')
        if not self.views:
            raise ValueError('views must name at least one drone')
        if self.drones_per_process < 0:
            raise ValueError('drones_per_process must be >= 0')
        if not 0 <= self.drone_niceness <= 19:
            raise ValueError(f'drone_niceness must be in [0, 19], got {self.drone_niceness}')
        if self.sync_timeout <= 0 or self.lockstep_timeout <= 0 or self.rate <= 0 or self.lockstep_window < 1:
            raise ValueError('sync_timeout, lockstep_timeout and rate must be positive, lockstep_window >= 1')
        topics.parse_remaps(self.remap)


@dataclass
class NodeSpec:
    """One process of the graph: what ``launch_ros.actions.Node`` takes (and ``ros2 run`` would start).

    ``param_files`` are ROS parameter YAML files applied first; ``parameters`` override them. A process of
    several nodes (``drone``) keeps their own names (``renamed`` false: ``__node`` would rename them all) and
    takes ``remaps``, e.g. ``{'calib:__node': 'calib_2'}`` (a rule for the node named calib only). ``niceness``
    > 0 starts the process through ``nice`` (:attr:`prefix`, launch's ``prefix``).
    """

    package: str
    executable: str
    name: str
    namespace: str = ''
    parameters: dict = field(default_factory=dict)
    param_files: list = field(default_factory=list)
    renamed: bool = True
    remaps: dict = field(default_factory=dict)
    niceness: int = 0

    @property
    def prefix(self) -> list:
        """Command words before the executable: ``nice -n N`` (which execs it: the same process id)."""
        return ['nice', '-n', str(self.niceness)] if self.niceness else []

    @property
    def label(self) -> str:
        """'D3/calib', 'fuse', ...: unique within a graph (log file names)."""
        return f'{self.namespace}/{self.name}' if self.namespace else self.name

    def ros_args(self) -> list:
        """Command-line form: ``--ros-args -r __node:=NAME [-r __ns:=/NS] [--params-file F] -p k:=v ...``."""
        args = ['--ros-args', *(['-r', f'__node:={self.name}'] if self.renamed else [])]
        for rule in self.remaps.items():
            args += ['-r', ':='.join(rule)]
        if self.namespace:
            args += ['-r', f'__ns:=/{self.namespace}']
        for path in self.param_files:
            args += ['--params-file', str(path)]
        for key, value in self.parameters.items():
            args += ['-p', f'{key}:={_param_text(value)}']
        return args


def _param_text(value) -> str:
    """A parameter value as ``-p`` parses it (YAML): a launch-argument string, lists in brackets, a string that
    YAML would read as something else quoted (``{view}/image``: a mapping to YAML)."""
    text = setting_to_string(value)
    if isinstance(value, (list, tuple)):
        return f'[{text}]'
    if isinstance(value, str) and _yaml_reads(text) != value:
        return "'" + value.replace("'", "''") + "'"
    return text


def _yaml_reads(text: str):
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return None


def share_file(package: str, *parts: str) -> str:
    """A file installed under ``share/<package>/`` (as FindPackageShare finds it)."""
    from ament_index_python.packages import get_package_share_directory

    return str(Path(get_package_share_directory(package), *parts))


# A drone's recorded streams the player plays: its images and the ground truth. Others (a camera driver's
# <drone>/camera_info, a recording's homography or pose) are the graph's own outputs and are not replayed.
PLAYED_DRONE_STREAMS = (
    topics.IMAGE_RAW,
    topics.IMAGE_COMPRESSED,
    topics.GROUND_TRUTH_CAMERA_INFO,
    topics.GROUND_TRUTH_POSE,
)
GRAPH_OUTPUTS = (*RECORDED, topics.FRAME_DONE_TOPIC, '/clock')  # scene-wide topics a bag's copy of is not played


@dataclass(frozen=True)
class BagFacts:
    """What the graph needs to know of the bag: image transport, frame count and the topics to play (as the bag
    names them: the chosen views' images and ground truth, and the scene-wide ones; empty = all), the names
    after ``remap`` (:func:`matrix_core.topics.parse_remaps`)."""

    compressed: bool
    frames: int
    has_ground_truth: bool
    topics: tuple = ()
    drones: tuple = ()  # every drone the bag's topics name (matrix_core.site.parameter.recorded_drones)

    @classmethod
    def read(cls, bag: str, views, remap=()) -> 'BagFacts':
        if not (Path(bag) / 'metadata.yaml').is_file():
            raise FileNotFoundError(f'not a rosbag2 folder (no metadata.yaml): {bag!r}')
        recorded, damage = topic_counts(bag)  # a damaged bag: what it holds before the damage (the player plays
        if damage:  # that and exits with code 4)
            _log.warning(f'{damage}: replaying the frames before the damage')
        rules = topics.parse_remaps(remap)
        named = {topics.remapped(n, rules): n for n in recorded}  # the graph's name -> the bag's
        counts = {n: recorded[b] for n, b in named.items()}
        imaged = {
            n.split('/')[1] for n in counts if n.endswith(('/' + topics.IMAGE_RAW, '/' + topics.IMAGE_COMPRESSED))
        }
        unknown = [v for v in views if v not in imaged]
        if unknown:
            raise ValueError(
                f'{bag}: no images of view(s) {", ".join(unknown)} in this bag; '
                f'it has images of {", ".join(sorted(imaged)) or "no view"}'
            )
        raw = [counts[n][1] for v in views if (n := topics.image_topic(v)) in counts]
        compressed = [counts[n][1] for v in views if (n := topics.image_topic(v, compressed=True)) in counts]
        if len(raw) + len(compressed) != len(views) or (raw and compressed):
            raise ValueError(
                f'{bag}: expected one image topic per view ({views}), all raw or all compressed; '
                f'it has {sorted(n for n in counts if "image" in n)}'
            )
        gt = all(topics.camera_info_topic(v) in counts for v in views)
        drones = recorded_drones(counts)
        played = tuple(sorted(named[n] for n in counts if _played(n, views, drones)))
        return cls(bool(compressed), max(raw or compressed), gt, played, tuple(drones))


def _played(name: str, views, drones) -> bool:
    """Whether the player plays the topic the graph names ``name``: a chosen view's images and ground truth,
    and every scene-wide topic that is not one of the graph's outputs."""
    drone, _, stream = name.strip('/').partition('/')
    if drone in drones:
        return drone in views and stream in PLAYED_DRONE_STREAMS
    return name not in GRAPH_OUTPUTS


def player_exit_text(code: int) -> str:
    """What the bag player's exit code means (matrix_ros.bag_player), for run_graph's and the launch's logs."""
    return {
        0: ' (every frame played and processed)',
        1: ' (nothing was played)',
        3: ' (lockstep timed out for some frame)',
        4: ' (the bag is damaged: only the frames before the damage were played)',
    }.get(code, '')


def graph_nodes(s: GraphSettings, bag: BagFacts = None) -> list:
    """The graph's processes, in start order (the player last: it waits for the others' subscriptions)."""
    from matrix_core.calib.scene import config_for_dataset

    site = named_site(s.site)  # before anything starts: a bad site file, drones the site lacks
    check_sources(s, site)
    if bag is None:
        if (Path(s.bag) / 'metadata.yaml').is_file():  # another site's recording: said before its missing views
            check_drones(site, recorded_drones(_graph_names(s)), f'bag {s.bag}')
        bag = BagFacts.read(s.bag, s.views, s.remap)
    check_drones(site, s.views, 'views')
    check_drones(site, bag.drones, f'bag {s.bag}')
    monitor = s.monitor and bag.has_ground_truth  # without ground truth: no scores (monitor_skipped says so)
    sim = {'use_sim_time': True}
    on_site = {'site': s.site}  # every node that takes the site: the same one
    # without a dataset folder each drone's references are the site file's
    references = {'site_references': not s.dataset}
    matrix_scene = site.path == matrix_site().path and s.dataset
    calib = {
        'config': s.calib_config or (str(config_for_dataset(s.dataset)) if matrix_scene else ''),
        'prior_dataset': s.dataset,
        **references,
        'qos': 'reliable',
        'compressed': bag.compressed,
        'use_registration': s.calib_registration,
        **on_site,
        **sim,
    }
    if s.calib_registration and s.lockstep:  # as the fuse node: wait as long as the player, deterministic
        calib['registration_wait_s'] = s.lockstep_timeout
    register = {'reference_dataset': s.dataset, **references, 'compressed': bag.compressed, **on_site, **sim}
    register_files = [s.register_params or share_file('matrix_register', 'config', 'register.yaml')]
    size = s.drones_per_process or len(s.views)
    groups = [list(s.views[i : i + size]) for i in range(0, len(s.views), size)]
    nodes = []
    for k, group in enumerate(groups, 1):
        ns = group[0] if size == 1 else ''
        suffix = f'_{k}' if size > 1 and len(groups) > 1 else ''
        if s.drone_process:  # one process, the nodes keep their names: /Dn/calib, /Dn/register, calib_2, ...
            nodes.append(
                NodeSpec(
                    'matrix_bringup',
                    'drone',
                    f'drone{suffix}',
                    ns,
                    {**calib, **register, 'views': group},
                    register_files,
                    renamed=False,
                    remaps={f'{n}:__node': f'{n}{suffix}' for n in DRONE_NODES if suffix},
                    niceness=s.drone_niceness,
                )
            )
            continue
        nodes += [
            NodeSpec(
                'matrix_calib', 'calib', f'calib{suffix}', ns, {**calib, 'views': group}, niceness=s.drone_niceness
            ),
            NodeSpec(
                'matrix_register',
                'register',
                f'register{suffix}',
                ns,
                {**register, 'views': group},
                register_files,
                niceness=s.drone_niceness,
            ),
        ]
    # In lockstep the fuse node waits as long as the player: every view is fused, results are deterministic.
    fuse = {
        'views': list(s.views),
        'input_kind': s.input_kind,
        'image_kind': 'compressed' if bag.compressed else 'raw',
        'sync_timeout': s.lockstep_timeout if s.lockstep else s.sync_timeout,
        'scene_dataset': s.dataset,
        **references,
        **({'overlay': True} if s.overlay or s.live_view else {}),
        **({'checkpoint': s.checkpoint} if s.checkpoint else {}),
        **on_site,
        **sim,
    }
    nodes.append(
        NodeSpec(
            'matrix_bev_tracker',
            'fuse',
            'fuse',
            '',
            fuse,
            [s.fuse_params or share_file('matrix_bev_tracker', 'config', 'fuse.yaml')],
        )
    )
    if s.live_view:
        nodes.append(
            NodeSpec(
                'matrix_live_view',
                'live_view',
                'live_view',
                '',
                {'views': list(s.views), 'port': s.live_view_port, 'scene_dataset': s.dataset},
            )
        )
    if s.record:
        per_view = PER_VIEW_RECORDED + ((OVERLAY_RECORDED,) if s.overlay else ())
        recorded = [*RECORDED, *(topics.absolute(v, stream) for v in s.views for stream in per_view)]
        nodes.append(
            NodeSpec(
                'matrix_ros',
                'recorder',
                'recorder',
                '',
                {
                    'out': s.record,
                    'topics': recorded,
                    'types': [topics.topic_type(n) for n in recorded],
                    'tracks_topic': topics.graph_topic(topics.TRACKS),
                    'sequence_bag': str(s.bag),
                    **sim,
                },
            )
        )
    if monitor:
        nodes.append(
            NodeSpec(
                'matrix_bringup',
                'graph_monitor',
                'graph_monitor',
                '',
                {
                    'views': list(s.views),
                    'expected_frames': bag.frames,
                    'wait_for': ['register', 'calib', 'tracks'],
                    'idle_timeout': s.lockstep_timeout,
                    'out_dir': s.monitor_out,
                    'reference_dataset': s.dataset,
                    **references,
                    **on_site,
                },
            )
        )
    # Every image topic is read by calib and register (or drone) and fuse (the monitor reads raw images too).
    readers = (2 if s.drone_process else 3) + (1 if monitor and not bag.compressed else 0)
    player = {
        'bag': s.bag,
        'rate': s.rate,
        'wait_for_subscribers': readers,
        'lockstep': s.lockstep,
        'lockstep_timeout': s.lockstep_timeout,
        'lockstep_window': s.lockstep_window,
        **({'topics': list(bag.topics)} if bag.topics else {}),
        **on_site,
    }
    if s.lockstep:
        done = topics.FRAME_DONE_TOPIC if monitor else topics.graph_topic(topics.TRACKS)
        player.update({'lockstep_topic': done, 'lockstep_type': topics.topic_type(done)})
    nodes.append(NodeSpec('matrix_ros', 'bag_player', 'bag_player', '', player, remaps=topics.parse_remaps(s.remap)))
    return nodes


def check_sources(s: GraphSettings, site) -> None:
    """ValueError, before anything starts, when the graph has no bag, or neither a dataset folder nor a site
    with references (``references.source: files``) to take each drone's references from."""
    from matrix_core.site.schema import ReferenceSource

    if not s.bag:
        raise ValueError('bag is required')
    if not s.dataset and site.references is ReferenceSource.SIMULATE:
        raise ValueError(
            f'dataset is required: site {site.name} ({site.path}) has no references (references.source: simulate); '
            f'give the dataset folder the bag came from, or the site.yaml of a site dataset or of site init'
        )


def monitor_skipped(s: GraphSettings, bag: BagFacts = None) -> str:
    """Why ``monitor`` runs no evaluation on this bag ('' when it does, or was not asked for): the bag holds no
    ground truth (``<drone>/ground_truth/camera_info``) for every view; the graph then runs without it."""
    if not s.monitor:
        return ''
    bag = bag or BagFacts.read(s.bag, s.views, s.remap)
    if bag.has_ground_truth:
        return ''
    lacking = [v for v in s.views if topics.camera_info_topic(v) not in _graph_names(s)]
    return (
        f'evaluation skipped: {s.bag} has no ground truth ({topics.GROUND_TRUTH_CAMERA_INFO}) of '
        f'{", ".join(lacking)}; the graph runs without graph_monitor scores'
    )


def _graph_names(s: GraphSettings) -> set:
    rules = topics.parse_remaps(s.remap)
    return {topics.remapped(n, rules) for n in topic_counts(s.bag)[0]}
