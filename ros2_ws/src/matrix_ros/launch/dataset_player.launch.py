"""Publish a MATRIX-format folder as per-view image and ground-truth CameraInfo topics.

Every launch argument is a parameter of the node (``matrix_ros.dataset_player.DatasetPlayerSettings``: same
names, defaults and descriptions); ``dataset`` is required.
"""

from matrix_ros.dataset_player import DatasetPlayerSettings
from matrix_ros.launch_settings import settings_launch_description


def generate_launch_description():
    return settings_launch_description('matrix_ros', 'dataset_player', DatasetPlayerSettings, required=('dataset',))
