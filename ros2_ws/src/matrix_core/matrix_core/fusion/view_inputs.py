"""One frame's messages of each view -> :class:`~matrix_core.fusion.views.ViewInput`: the ground homography
from the view's geometry message and the image decoded at the scale the network needs.

Message-agnostic (``matrix_core.message_fields`` reads rclpy and rosbags messages alike), so the fuse node
only subscribes and hands the messages over. Geometry:

- ``matrix_msgs/HomographyStamped`` (from ``register``): its :class:`Registration`; a view is missing when
  the registration failed or is unusable, or its confidence is below ``min_confidence``;
- ``sensor_msgs/CameraInfo`` (``p = K [R | t]``, from ``calib`` or a bag's ground truth): its camera; an
  image of another size than the CameraInfo's makes the view missing.

Images may be decoded as they arrive (:meth:`ViewInputs.decode_early`), while the drones still register and
calibrate that frame, and made into the network's input there too (the same function the fuser would call on
the same image, so the results do not change): neither then sits between the frame's last homography and its
tracks. The first frame gains most: each view's first image is decoded and resized in full (see ``_decode``).
"""

from dataclasses import dataclass

from matrix_core.bev.data import prepare_image
from matrix_core.fusion.views import (
    FrameStatus,
    ViewInput,
    ViewInputError,
    at_reduced_resolution,
    check_image,
    jpeg_reduction,
)
from matrix_core.message_fields import (
    ConversionError,
    camera_from_camera_info,
    image_from_msg,
    is_jpeg,
    registration_from_msg,
)
from matrix_core.register.registration import RegistrationError, RegistrationStatus


NOT_SENT = 'no image: dropped at the sender (link budget)'
EARLY_KEPT = 64  # early decodes kept for frames not fused yet (8 views x 8 frames); the oldest go first


@dataclass(frozen=True)
class ImageNotSent:
    """Stands in for an image its drone said it did not send (``link_sender`` dropped the frame before its
    link), so that the frame need not wait for it. ``header``: the notice's (the frame's stamp)."""

    header: object


def registration_ground(registration, min_confidence: float):
    """(3, 3) ``img_H_ground`` of a registration a view may use; :class:`ViewInputError` saying why not."""
    if registration.status in (RegistrationStatus.FAILED, RegistrationStatus.BAD_INPUT):
        raise ViewInputError(f'registration {registration.status}: {registration.message}')
    if registration.ok and registration.confidence < min_confidence:
        raise ViewInputError(f'registration confidence {registration.confidence:.2f} < {min_confidence}')
    try:
        return registration.img_H_ground
    except RegistrationError as exc:
        raise ViewInputError(registration.message or str(exc)) from None


class ViewInputs:
    """Builds the views of each frame; remembers each view's full image size for the reduced JPEG decode.

    Args:
        input_size: (w, h) of the network input.
        min_confidence: registrations below it are not used.
        reduced_decode: decode JPEGs directly at 1/2, 1/4 or 1/8 size when that still covers ``input_size``
            (once a full decode told the view's image size).
    """

    def __init__(self, input_size: tuple, min_confidence: float, reduced_decode: bool):
        self.input_size, self.min_confidence, self.reduced_decode = input_size, min_confidence, reduced_decode
        self.full_size = {}  # view -> (w, h) of its last fully decoded image
        self._early = {}  # id(msg) -> (msg, (image, r, full size), network input): made on arrival, not used yet
        self._deferred = {}  # id(msg) -> (view, msg): arrived while an earlier frame waited, not decoded yet

    def decode_early(self, view: str, msg, defer: bool = False) -> None:
        """Decode ``msg``, one of ``view``'s images, now; :meth:`view_input` takes it from here. A message that
        does not decode is left for :meth:`view_input`, which says why the view is missing. ``defer`` (an earlier
        frame still waits for its homographies): keep it for :meth:`decode_deferred` instead, so that the decode
        does not take the cores from the registrations that earlier frame waits for."""
        if msg is None or isinstance(msg, ImageNotSent):
            return
        if defer:
            self._deferred[id(msg)] = (view, msg)
            return
        try:
            decoded = self._decode(view, msg)
            network_image = prepare_image(check_image(decoded[0]), self.input_size)
        except (ViewInputError, ConversionError):
            return
        self._early[id(msg)] = (msg, decoded, network_image)  # the message kept: its id stays unique
        while len(self._early) > EARLY_KEPT:
            del self._early[next(iter(self._early))]

    def decode_deferred(self) -> None:
        """Decode now the images :meth:`decode_early` deferred (a frame was just fused)."""
        deferred, self._deferred = self._deferred, {}
        for view, msg in deferred.values():
            self.decode_early(view, msg)

    def frame_views(self, items: dict, views: list, geometry_name: str) -> dict | None:
        """Every view's :class:`ViewInput` from a synchronised frame's items (``'V/image'``, ``'V/geometry'``);
        None when no view has an image at all (e.g. geometry history replayed after a restart): nothing to see."""
        if not any(f'{v}/image' in items for v in views):
            return None
        return {
            v: self.view_input(v, items.get(f'{v}/image'), items.get(f'{v}/geometry'), geometry_name) for v in views
        }

    def view_input(self, view: str, image_msg, geometry_msg, geometry_name: str) -> ViewInput:
        """One view's :class:`ViewInput`; any problem becomes its reason. ``geometry_name`` names the missing
        geometry in that reason (e.g. 'homography')."""
        if isinstance(image_msg, ImageNotSent):
            return ViewInput(reason=NOT_SENT, status=FrameStatus.MISSING)
        _, early, network_image = self._early.pop(id(image_msg), (None, None, None))
        self._deferred.pop(id(image_msg), None)  # its frame came before its deferred decode: decoded below
        if image_msg is None or geometry_msg is None:
            return ViewInput(
                reason='no '
                + ' and no '.join(p for p, x in (('image', image_msg), (geometry_name, geometry_msg)) if x is None),
                status=FrameStatus.MISSING,
            )
        confidence, camera_size = None, None
        try:
            if hasattr(geometry_msg, 'h_img_to_ground'):
                registration = registration_from_msg(geometry_msg)
                confidence = float(registration.confidence)
                img_H_ground = registration_ground(registration, self.min_confidence)
            else:
                camera = camera_from_camera_info(geometry_msg)
                img_H_ground, camera_size = camera.img_H_ground(), (camera.width, camera.height)
            image, r, full = early or self._decode(view, image_msg)
            if camera_size is not None and full != camera_size:
                # its homography is for other pixels: lifting would put the features in the wrong cells
                raise ViewInputError('image is {}x{}, its camera_info is for {}x{}'.format(*full, *camera_size))
        except (ViewInputError, ConversionError) as exc:
            return ViewInput(reason=str(exc), confidence=confidence, status=FrameStatus.REJECTED)
        return ViewInput(
            image,
            img_H_ground if r == 1 else at_reduced_resolution(img_H_ground, r),
            confidence=confidence,
            network_image=network_image,
        )

    def _decode(self, view: str, msg) -> tuple:
        """(image, r, (w, h) of the full image): the image decoded at 1/r, a JPEG at the smallest libjpeg scale
        that keeps the network input once a full decode told the view's image size (r = 1 otherwise).

        A view's first image is decoded in full, as the offline evaluation decodes every frame: the tracks start
        from it. Decoding it reduced too (its size from the JPEG header) saved the live graph's first frame ~0.1
        CPU s in fuse, but moved `make demo`'s simulated live IDF1 from 0.96 to 1.07 points below offline (91.18
        -> 91.07 against 92.14; MOTA 86.04 -> 85.83 against 86.67; stops 37 and 44), beyond the 1 point allowed."""
        full = self.full_size.get(view)
        if hasattr(msg, 'format') and self.reduced_decode and full and is_jpeg(msg):
            r = jpeg_reduction(full, self.input_size)
            if r > 1:
                image = image_from_msg(msg, r)
                if (image.shape[1], image.shape[0]) == (-(-full[0] // r), -(-full[1] // r)):
                    return image, r, full
                # the stream's image size changed: decode in full and learn the new size
        image = image_from_msg(msg)
        self.full_size[view] = (image.shape[1], image.shape[0])
        return image, 1, self.full_size[view]
