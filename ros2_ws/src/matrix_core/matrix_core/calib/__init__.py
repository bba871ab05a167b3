"""Per-drone camera calibration from ground checkerboards, every frame (pure core, no ROS).

:class:`matrix_core.calib.drone_calibrator.DroneCalibrator` calibrates one drone, frame after frame (ok / stale /
failed); where it predicts the boards from and which strategy it tries first:
``guided`` (the camera the frame's registration implies) or ``motion`` (the prior pose carried into the image by
the ORB ground homography) -> ``corner_tracking`` (the predicted corners refined and verified, no search) or
``board_search``: ``regions`` (each board predicted, rectified view) -> ``detection`` (partial grids,
``findChessboardCornersSB``; the whole image when nothing is found) -> ``assignment`` (which board corner each
detected corner is: prior prediction + checker colours, ambiguous pieces rejected) -> ``pnp`` (RANSAC +
Levenberg-Marquardt) -> ``grow`` (all board corners refined and verified, whole-square correction from the board
edges). ``scene`` loads the YAML config, ``settings`` holds the thresholds (CLI flags and ROS parameters).
"""
