"""Register each drone's image to its reference image and publish /<view>/homography: one ``register``
node hosting the listed drones (all eight by default).

Every launch argument is a parameter of the node (``matrix_register.settings.RegisterNodeSettings``:
same names, defaults and descriptions; ``ros2 launch matrix_register register.launch.py --show-args``).
"""

from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS
from matrix_register.settings import RegisterNodeSettings
from matrix_ros.launch_settings import settings_launch_description


def generate_launch_description():
    return settings_launch_description(
        'matrix_register', 'register', RegisterNodeSettings, defaults={'views': list(MATRIX_VIEWS)}
    )
