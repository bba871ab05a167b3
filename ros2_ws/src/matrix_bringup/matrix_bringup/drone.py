"""``drone``: one drone's ``register`` and ``calib`` nodes in one process (``GraphSettings.drone_process``).

The process subscribes the drone's images once (register's subscription); each image is decoded once, full
size and grey, registered, and handed with its registration to calib in process (``matrix_ros.drone_link``):
no second subscription, no second decode, no registration waiting on DDS. Topics, diagnostics and node names
are those of the two nodes alone (``V/homography`` still goes out for fuse and the others), and so are the
parameters: the process takes the parameters of both nodes (``ros2 run matrix_bringup drone --ros-args -p
views:=[D3] -p config:=... -p reference_dataset:=...``), each node the ones it has (the names they share,
``views``, ``compressed``, ``qos``, ..., set both).

    ros2 run matrix_bringup drone --ros-args -r __ns:=/D3 -p use_registration:=true -p ...
"""

from matrix_calib.calib_node import CalibNode
from matrix_calib.settings import CalibNodeSettings
from matrix_core.settings import settings_fields
from matrix_register.register_node import RegisterNode
from matrix_register.settings import RegisterNodeSettings
from matrix_ros.drone_link import DroneLink
from matrix_ros.params import spin_nodes


# The settings of the nodes this process hosts: one parameter set is given to all of them, so a name they
# share must mean the same in each (test_process_settings.py checks type, default and help).
HOSTED_SETTINGS = (RegisterNodeSettings, CalibNodeSettings)


def main(argv=None) -> int:
    link = DroneLink([name for cls in HOSTED_SETTINGS for name, *_ in settings_fields(cls)])
    # register first: calib connects to the link before any image can arrive (nothing spins until both exist)
    nodes = [lambda: RegisterNode(RegisterNodeSettings(), link), lambda: CalibNode(CalibNodeSettings(), link)]
    return spin_nodes(nodes, argv, description=__doc__)


if __name__ == '__main__':
    raise SystemExit(main())
