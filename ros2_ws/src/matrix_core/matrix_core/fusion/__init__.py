"""Live multi-view BEV fusion: one synchronised frame of per-view images and calibrations -> detections,
tracks and the heatmap (the core of the ``fuse`` node; no ROS here).

Import the submodules directly: ``fusion.settings`` and ``fusion.views`` are light (no torch);
``fusion.fuser`` loads the network.
"""
