"""A site's calibration scene (``matrix_core.calib.scene.CalibScene``): its boards, and the camera of one drone
or the one camera all its drones share. The calib node (``config`` empty) and ``matrix-tracker site init`` take
their boards from here, so that a site's boards are written once, in its site file."""

from matrix_core.calib.scene import CalibScene, load_scene, scene_from_dict
from matrix_core.site.load import SiteError
from matrix_core.site.schema import DroneSpec, Site
from matrix_core.site.shipped import matrix_site


def _camera_keys(camera) -> dict:
    return {
        'image_size': list(camera.image_size),
        'intrinsics': {'K': [float(v) for v in camera.K.ravel()], 'dist': [float(v) for v in camera.dist]},
    }


def site_calib_scene(site: Site, drone: DroneSpec = None) -> CalibScene:
    """The boards of ``site`` with ``drone``'s camera (or, without a drone, the camera its drones share).

    The MATRIX site's scene is the shipped real-sample config (``load_scene()``, whose boards are the site's),
    so that a node given no site calibrates as it always did. SiteError naming the site when it has no boards
    or, without a drone, when its drones' cameras differ."""
    if drone is None and site.path == matrix_site().path:
        return load_scene()
    if not site.boards:
        raise SiteError(f'{site.path}: boards: none; calibration needs at least one checkerboard')
    data = {'site': str(site.path), **(_camera_keys(drone.camera) if drone is not None else {})}
    try:
        return scene_from_dict(data, str(site.path), site.path.parent)
    except ValueError as exc:
        raise SiteError(str(exc)) from None
