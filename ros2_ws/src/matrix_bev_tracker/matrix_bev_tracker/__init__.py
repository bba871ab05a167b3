"""Bird's-eye-view multi-view fusion network and tracker: publishes detections and tracks."""
