"""Topic names, message types and frame ids of sequence bags (see the package docstring)."""

WORLD_FRAME = 'world'
PEDESTRIANS_TOPIC = '/ground_truth/pedestrians'
PEDESTRIAN_IDS_TOPIC = '/ground_truth/pedestrian_ids'

IMAGE_TYPE = 'sensor_msgs/msg/Image'
COMPRESSED_TYPE = 'sensor_msgs/msg/CompressedImage'
CAMERA_INFO_TYPE = 'sensor_msgs/msg/CameraInfo'
POSE_TYPE = 'geometry_msgs/msg/PoseStamped'
POSE_ARRAY_TYPE = 'geometry_msgs/msg/PoseArray'
IDS_TYPE = 'std_msgs/msg/Int32MultiArray'


def image_topic(view: str, compressed: bool = False) -> str:
    """'/D1/image_raw' or '/D1/image/compressed'."""
    return f'/{view}/image/compressed' if compressed else f'/{view}/image_raw'


def camera_info_topic(view: str) -> str:
    return f'/{view}/ground_truth/camera_info'


def pose_topic(view: str) -> str:
    return f'/{view}/ground_truth/pose'


def optical_frame(view: str) -> str:
    return f'{view}/camera_optical'
