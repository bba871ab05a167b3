"""Per-drone camera calibration from ground checkerboards, every frame (PnP).

Publishes CameraInfo, pose and diagnostics."""
