"""Feature-based registration of each drone's current image to its reference image.

Pipeline (one idea per module): ``backends`` (registry of feature backends: ``backend_sift``,
``backend_kornia``) -> ``matching`` (symmetric ratio test) -> ``fit`` (RANSAC/MAGSAC homography) ->
``gate`` (physical sanity checks) -> ``registration`` (the contract every consumer reads); ``reference``
caches the reference's ground features (``ground_mask``; obstacles and ground extent from the dataset:
``scene``) and key frames; ``registrar`` ties it together per drone (mode ``track``: ``flow_tracking``
registers the frames between full registrations by optical flow); ``evaluate`` computes the acceptance
error from the stored calibrations, ``acceptance`` runs it over a whole folder; ``overlay`` draws the pictures.
"""

from matrix_core.register.registration import Registration, RegistrationError
from matrix_core.register.settings import RegisterSettings

__all__ = ['RegisterSettings', 'Registration', 'RegistrationError']
