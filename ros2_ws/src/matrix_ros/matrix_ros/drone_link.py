"""One drone's calib and register nodes in one process (``matrix_bringup.drone``): each image is decoded once
and its registration handed to calib in process.

register subscribes the drone's images (the process's only image subscription) and decodes each one once,
full size and grey: calib needs the full resolution (board rows are 3-6 px apart,
``matrix_core.calib.detection``), register resizes the same grey image to its ``scale`` (its features are grey
too). register hands calib the decoded image (:meth:`DroneLink.image`), then the very registration message it
publishes on ``V/homography`` for fuse and the others (:meth:`DroneLink.registration`); calib subscribes
neither stream and pairs the two exactly as if they had come over DDS. A node alone has an unconnected link:
it decodes colour images itself and hands nothing on.
"""

from matrix_ros.conversions import gray_image_from_msg, msg_to_image


class DroneLink:
    """The in-process hand-over from register to calib.

    Args:
        parameters: every parameter name of the nodes sharing the process: each node accepts the others'
            (one parameter set is given to the whole process; the names the nodes share mean the same).
    """

    def __init__(self, parameters=()):
        self.parameters = tuple(parameters)
        self._on_image = self._on_registration = None

    @property
    def shared(self) -> bool:
        """Whether calib takes its images and registrations from here (instead of subscribing them)."""
        return self._on_image is not None

    def connect(self, on_image, on_registration) -> 'DroneLink':
        """calib's side: ``on_image(view, msg, image)`` and ``on_registration(view, HomographyStamped)``."""
        self._on_image, self._on_registration = on_image, on_registration
        return self

    def decode(self, msg):
        """register's image: (H, W) grey full size when shared, else (H, W, 3) BGR (as a node alone decodes)."""
        return gray_image_from_msg(msg) if self.shared else msg_to_image(msg)

    def image(self, view: str, msg, image) -> None:
        """register received ``msg`` of ``view``, decoded as ``image`` (None: undecodable; calib decodes it
        itself and reports the bad input)."""
        if self.shared:
            self._on_image(view, msg, image)

    def registration(self, view: str, msg) -> None:
        """register published ``msg`` (HomographyStamped, ok or failed) for an image of ``view``."""
        if self.shared:
            self._on_registration(view, msg)
