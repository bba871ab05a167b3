"""Topic names, message types and frame ids: the one stream convention of nodes, bags, player and recorder.

Per-drone streams are RELATIVE names under the drone, ``<view>/<stream>`` (e.g. ``D3/image_raw``): a node
in the root namespace resolves them to ``/D3/image_raw``, one started in a namespace (``--ros-args -r
__ns:=/fleet``) to ``/fleet/D3/image_raw``, and each is remappable (``-r D3/image_raw:=/cam3/image``) as ROS
users expect. A node started in a drone's namespace (``/D3``, as ``run_graph`` starts one process per drone)
uses the bare stream names (``image_raw``) for that drone (``matrix_ros.node_settings.hosted_drones``).
Bags store the absolute names of a root-namespace graph (:func:`absolute`).
Graph-wide outputs (``tracks``, ``detections``, ...) are relative too; ``/diagnostics`` is absolute by ROS
convention.
"""

WORLD_FRAME = 'world'
DIAGNOSTICS_TOPIC = '/diagnostics'
# The pedestrian area's corner (x_min, y_min, 0) with the world's axes (REP 105 style fixed frame, /tf_static).
AREA_FRAME = 'area'
TF_TOPIC = '/tf'  # absolute by tf2 convention: calib's camera poses
TF_STATIC_TOPIC = '/tf_static'  # fuse's fixed frames (world -> area)

# Per-drone streams (relative to the drone).
IMAGE_RAW = 'image_raw'
IMAGE_COMPRESSED = 'image/compressed'
LINK_IMAGE_COMPRESSED = 'link/image/compressed'  # the images a drone sends across its link (link_sender)
LINK_DROPPED = 'link/dropped'  # the stamps of the frames link_sender did not send (Header)
CAMERA_INFO = 'camera_info'  # calib's per-frame calibration
POSE = 'pose'  # calib's camera pose
HOMOGRAPHY = 'homography'  # register's registration
GROUND_TRUTH_CAMERA_INFO = 'ground_truth/camera_info'
DETECTIONS_2D = 'detections_2d'  # fuse's boxes of the tracks in the drone's image
OVERLAY_COMPRESSED = 'overlay/compressed'  # fuse's overlay: the image with those boxes and ids (JPEG)
GROUND_TRUTH_POSE = 'ground_truth/pose'

# Graph-wide streams.
TRACKS = 'tracks'
DETECTIONS = 'detections'
MARKERS = 'markers'
BEV_HEATMAP = 'bev_heatmap'
PEDESTRIANS_TOPIC = '/ground_truth/pedestrians'
PEDESTRIAN_IDS_TOPIC = '/ground_truth/pedestrian_ids'

# The outputs again in the standard perception types (vision_msgs), for stacks that know none of ours
# (docs/standard-interfaces.md): graph-wide, and per drone (``Dn/vision/detections_2d``).
VISION_TRACKS = 'vision/tracks'  # Detection3DArray, id = the track id
VISION_DETECTIONS = 'vision/detections'  # Detection3DArray, no id
VISION_DETECTIONS_2D = 'vision/detections_2d'  # Detection2DArray of a drone's image, id = the fused track id
PERSON_CLASS_ID = 'person'  # ObjectHypothesis.class_id of every detection (the COCO name detectors use)
LIVE_VIEW_PORT = 8765  # the live view's Foxglove WebSocket server (ws://HOST:8765)

IMAGE_TYPE = 'sensor_msgs/msg/Image'
COMPRESSED_TYPE = 'sensor_msgs/msg/CompressedImage'
CAMERA_INFO_TYPE = 'sensor_msgs/msg/CameraInfo'
POSE_TYPE = 'geometry_msgs/msg/PoseStamped'
POSE_ARRAY_TYPE = 'geometry_msgs/msg/PoseArray'
IDS_TYPE = 'std_msgs/msg/Int32MultiArray'
HEADER_TYPE = 'std_msgs/msg/Header'
HOMOGRAPHY_TYPE = 'matrix_msgs/msg/HomographyStamped'
TRACK_ARRAY_TYPE = 'matrix_msgs/msg/TrackArray'
DETECTION_2D_ARRAY_TYPE = 'matrix_msgs/msg/Detection2DArray'
DETECTION_3D_ARRAY_TYPE = 'vision_msgs/msg/Detection3DArray'
VISION_DETECTION_2D_ARRAY_TYPE = 'vision_msgs/msg/Detection2DArray'
TF_TYPE = 'tf2_msgs/msg/TFMessage'
MARKER_ARRAY_TYPE = 'visualization_msgs/msg/MarkerArray'
OCCUPANCY_GRID_TYPE = 'nav_msgs/msg/OccupancyGrid'
DIAGNOSTIC_ARRAY_TYPE = 'diagnostic_msgs/msg/DiagnosticArray'

FRAME_DONE_TOPIC = '/graph_monitor/frame_done'  # graph_monitor: the stamp of each frame every stage finished
PLAYER_START_TOPIC = '/bag_player/start'  # the wall time the players of every host start (start_signal)

# The message type of every stream: per drone, graph-wide (relative names) and absolute.
DRONE_STREAM_TYPES = {
    IMAGE_RAW: IMAGE_TYPE,
    IMAGE_COMPRESSED: COMPRESSED_TYPE,
    LINK_IMAGE_COMPRESSED: COMPRESSED_TYPE,
    LINK_DROPPED: HEADER_TYPE,
    CAMERA_INFO: CAMERA_INFO_TYPE,
    POSE: POSE_TYPE,
    HOMOGRAPHY: HOMOGRAPHY_TYPE,
    GROUND_TRUTH_CAMERA_INFO: CAMERA_INFO_TYPE,
    DETECTIONS_2D: DETECTION_2D_ARRAY_TYPE,
    OVERLAY_COMPRESSED: COMPRESSED_TYPE,
    GROUND_TRUTH_POSE: POSE_TYPE,
    VISION_DETECTIONS_2D: VISION_DETECTION_2D_ARRAY_TYPE,
}
GRAPH_STREAM_TYPES = {
    TRACKS: TRACK_ARRAY_TYPE,
    DETECTIONS: TRACK_ARRAY_TYPE,
    MARKERS: MARKER_ARRAY_TYPE,
    BEV_HEATMAP: OCCUPANCY_GRID_TYPE,
    VISION_TRACKS: DETECTION_3D_ARRAY_TYPE,
    VISION_DETECTIONS: DETECTION_3D_ARRAY_TYPE,
}
ABSOLUTE_TOPIC_TYPES = {
    DIAGNOSTICS_TOPIC: DIAGNOSTIC_ARRAY_TYPE,
    PEDESTRIANS_TOPIC: POSE_ARRAY_TYPE,
    PEDESTRIAN_IDS_TOPIC: IDS_TYPE,
    FRAME_DONE_TOPIC: HEADER_TYPE,
    TF_TOPIC: TF_TYPE,
    TF_STATIC_TOPIC: TF_TYPE,
    PLAYER_START_TOPIC: HEADER_TYPE,
}


def drone_topic(view: str, stream: str) -> str:
    """Relative name of a drone's stream: ('D3', 'image_raw') -> 'D3/image_raw'; ('', s) -> s (the node is
    inside the drone's namespace)."""
    return f'{view}/{stream}' if view else stream


def absolute(view: str, stream: str) -> str:
    """The name a root-namespace graph (and a bag) uses: ('D3', 'image_raw') -> '/D3/image_raw'."""
    return '/' + drone_topic(view, stream)


def graph_topic(stream: str) -> str:
    """The name a root-namespace graph uses for a graph-wide stream: 'tracks' -> '/tracks'."""
    return '/' + stream


def topic_type(topic: str) -> str:
    """The message type of a topic of a root-namespace graph: '/D3/homography' -> HOMOGRAPHY_TYPE,
    '/tracks' -> TRACK_ARRAY_TYPE, '/diagnostics' -> DIAGNOSTIC_ARRAY_TYPE. KeyError for a name that is none of
    the streams above (``/<view>/<drone stream>``, ``/<graph stream>`` or an absolute topic)."""
    if topic in ABSOLUTE_TOPIC_TYPES:
        return ABSOLUTE_TOPIC_TYPES[topic]
    view, _, stream = topic.removeprefix('/').partition('/')
    if topic.startswith('/') and view and stream in DRONE_STREAM_TYPES:
        return DRONE_STREAM_TYPES[stream]
    if topic.startswith('/') and topic[1:] in GRAPH_STREAM_TYPES:  # 'tracks', 'vision/tracks'
        return GRAPH_STREAM_TYPES[topic[1:]]
    raise KeyError(f'{topic!r} is not a topic of matrix_core.topics')


def image_stream(compressed: bool) -> str:
    return IMAGE_COMPRESSED if compressed else IMAGE_RAW


def image_topic(view: str, compressed: bool = False) -> str:
    """'/D1/image_raw' or '/D1/image/compressed' (bags)."""
    return absolute(view, image_stream(compressed))


def camera_info_topic(view: str) -> str:
    """Ground-truth CameraInfo of a bag: '/D1/ground_truth/camera_info'."""
    return absolute(view, GROUND_TRUTH_CAMERA_INFO)


def pose_topic(view: str) -> str:
    """Ground-truth pose of a bag: '/D1/ground_truth/pose'."""
    return absolute(view, GROUND_TRUTH_POSE)


def optical_frame(view: str) -> str:
    return f'{view}/camera_optical'


def parse_remaps(rules) -> dict:
    """ROS remapping rules ``FROM:=TO`` of absolute topic names (a recording's names -> the graph's, e.g.
    ``/cam_front/image:=/alpha/image_raw``) as a dict; ValueError naming a malformed rule."""
    out = {}
    for rule in rules:
        src, sep, dst = str(rule).partition(':=')
        if not sep or not src.startswith('/') or not dst.startswith('/') or ':=' in dst:
            raise ValueError(
                f'remap rule {rule!r}: expected FROM:=TO, two absolute topic names (/cam/image:=/a/image_raw)'
            )
        if src in out:
            raise ValueError(f'remap rule {rule!r}: {src} is remapped twice')
        out[src] = dst
    return out


def remapped(name: str, remaps: dict) -> str:
    """``name`` as the remapping rules (:func:`parse_remaps`) rename it (exact names, as ROS matches them)."""
    return remaps.get(name, name)
