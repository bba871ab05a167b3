"""Per-drone checkerboard calibration: one ``calib`` node hosting the listed drones (all eight by default).

Every launch argument is a parameter of the node (``matrix_calib.settings.CalibNodeSettings``: same names,
defaults and descriptions; ``ros2 launch matrix_calib calib.launch.py --show-args`` lists them).
"""

from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS
from matrix_calib.settings import CalibNodeSettings
from matrix_ros.launch_settings import settings_launch_description


def generate_launch_description():
    return settings_launch_description(
        'matrix_calib', 'calib', CalibNodeSettings, defaults={'views': list(MATRIX_VIEWS)}
    )
