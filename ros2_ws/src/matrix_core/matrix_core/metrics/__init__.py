"""Evaluation metrics in metres on the ground plane (detection: MODA/MODP; tracking: MOTA/IDF1/...; HOTA)."""

from matrix_core.metrics.bev_points import BevPoints, read_bev_points, write_bev_points
from matrix_core.metrics.detection import DetectionMetrics, detection_metrics
from matrix_core.metrics.hota import HotaMetrics, hota_metrics
from matrix_core.metrics.tracking import TrackingMetrics, tracking_metrics

__all__ = [
    'BevPoints',
    'read_bev_points',
    'write_bev_points',
    'DetectionMetrics',
    'detection_metrics',
    'TrackingMetrics',
    'tracking_metrics',
    'HotaMetrics',
    'hota_metrics',
]
