"""matrix-tracker core: algorithms and data layer, free of ROS.

Nothing in this package may import ``rclpy`` or a ROS message package; ``tests/test_core_purity.py``
enforces that. Nodes in the other packages are thin wrappers around these modules.
"""

__version__ = '0.1.0'
