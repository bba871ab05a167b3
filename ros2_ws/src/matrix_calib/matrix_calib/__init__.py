"""Per-drone camera calibration from ground checkerboards, every frame (PnP): publishes CameraInfo, pose and diagnostics."""
