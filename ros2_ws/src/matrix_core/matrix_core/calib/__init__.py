"""Per-drone camera calibration from ground checkerboards, every frame (pure core, no ROS).

Pipeline of one frame (see :class:`matrix_core.calib.tracker.DroneCalibrator`):
``motion`` (ORB ground homography since the prior's image) -> ``regions`` (each board predicted from the
prior pose, rectified view) -> ``detection`` (partial grids, ``findChessboardCornersSB``) -> ``assignment``
(which board corner each detected corner is: prior prediction + checker colours, ambiguous pieces rejected)
-> ``pnp`` (RANSAC + Levenberg-Marquardt) -> ``grow`` (all board corners refined and verified, whole-square
correction from the board edges) -> ``tracker`` (ok / stale / failed). ``scene`` loads the YAML config,
``settings`` holds the thresholds (CLI flags and ROS parameters).
"""
