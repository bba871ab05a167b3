"""BEV fusion network: shared CNN encoder, per-frame homography lifting, masked view aggregation,
temporal fusion, centre/offset/tracking heads; training, inference and evaluation.

Import the submodules directly (``matrix_core.bev.model``, ...); this package does not import torch
by itself, so ``matrix_core.bev.settings`` stays light for the ROS node's parameters.
"""
