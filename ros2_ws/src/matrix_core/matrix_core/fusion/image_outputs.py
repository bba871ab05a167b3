"""The fuse node's image-plane outputs, message-agnostic: each view's camera of a frame from the geometry
message the node fused it with, and the boxes of the frame's tracks in it (``fusion.image_boxes``).

Camera of a view for a frame (the simplest source that is exact for what the node fused):
    - ``sensor_msgs/CameraInfo`` (``p = K [R | t]``, calib or a bag's ground truth): that camera;
    - ``matrix_msgs/HomographyStamped`` (register): the camera the registration's ``img_H_ground`` implies
      (``Registration.implied_camera``) with the drone's intrinsics, and its image size, from the reference
      calibration of the scene dataset (``reference/calibrations`` of the MATRIX folder the graph replays,
      the references register registers to; intrinsics do not change in flight). Without a scene dataset
      a homography view has no camera (no image outputs).
A view without usable geometry this frame (missing, failed registration) has no camera: no boxes are
published for it. Obstacles: the scene dataset's own (simulated folders' meta), else ``obstacle_boxes``.
"""

from dataclasses import replace

import numpy as np

from matrix_core.fusion.image_boxes import ImageBoxSettings, image_boxes, implied_view_camera, obstacles_from_meta
from matrix_core.message_fields import ConversionError, camera_from_camera_info, registration_from_msg
from matrix_core.register.registration import RegistrationError


class ViewCameras:
    """Cameras of the views from their geometry messages, and the tracks' boxes in them.

    Args:
        settings: the person model and visibility rule.
        intrinsics: view -> (K (3, 3), (w, h)) for homography geometry (empty: CameraInfo only).
    """

    def __init__(self, settings: ImageBoxSettings, intrinsics: dict = None, unavailable: dict = None):
        self.settings, self.intrinsics = settings, dict(intrinsics or {})
        self.unavailable = dict(unavailable or {})  # view -> why it has no intrinsics (no boxes in it)

    @classmethod
    def from_dataset(cls, settings: ImageBoxSettings, root, views) -> 'ViewCameras':
        """Intrinsics from ``root``'s reference calibrations (those it has), obstacles from its meta. A view
        whose reference cannot be read gets no boxes (``unavailable`` says why); the others do."""
        from matrix_core.datasets.open import open_dataset

        return cls.from_references(settings, open_dataset(root), views)

    @classmethod
    def from_references(cls, settings: ImageBoxSettings, dataset, views) -> 'ViewCameras':
        """As :meth:`from_dataset`, from a source of references (``datasets.drone_inputs.open_references``: a
        dataset folder's, or a site file's)."""
        from matrix_core.datasets.types import DatasetError

        intrinsics, unavailable = {}, {}
        if getattr(dataset, 'has_reference', False):
            for v in views:
                try:
                    cam = dataset.reference_camera(v)
                except (DatasetError, OSError, ValueError) as exc:  # one drone's bad file: that drone only
                    unavailable[v] = f'reference: {exc}'
                    continue
                intrinsics[v] = (cam.K, (cam.width, cam.height))
        boxes = obstacles_from_meta(getattr(dataset, 'meta', None), settings.obstacle_boxes)
        return cls(replace(settings, obstacle_boxes=boxes), intrinsics, unavailable)

    def camera(self, view: str, geometry_msg):
        """The view's Camera from its geometry message, or None (no message, failed/unusable registration,
        no intrinsics for a homography view, or a malformed message)."""
        if geometry_msg is None:
            return None
        try:
            if not hasattr(geometry_msg, 'h_img_to_ground'):
                return camera_from_camera_info(geometry_msg)
            if view not in self.intrinsics:
                return None
            K, size = self.intrinsics[view]
            return implied_view_camera(registration_from_msg(geometry_msg).implied_camera(K), size)
        except (ConversionError, RegistrationError, ValueError):
            return None

    def frame_boxes(self, geometry: dict, tracks) -> dict:
        """view -> list of ImageBox (nearest first) for every view with a camera; ``geometry``: view -> its
        geometry message (or None); ``tracks``: TrackState-like (``track_id``, ``score``, ``detection_xy``
        or else ``xy``)."""
        ids = [t.track_id for t in tracks]
        xy = np.reshape([t.xy if getattr(t, 'detection_xy', None) is None else t.detection_xy for t in tracks], (-1, 2))
        scores = [t.score for t in tracks]
        out = {}
        for view, msg in geometry.items():
            camera = self.camera(view, msg)
            if camera is not None:
                out[view] = image_boxes(camera, ids, xy, scores, self.settings)
        return out
