"""Which live image becomes a drone's registration reference when no reference dataset is configured: the
first image whose calibration (a CameraInfo) has the SAME stamp, in whichever order the two arrive. A
calibration of another instant would make every homography wrong.

Pure and stamp-driven (stamps are integer nanoseconds): the register node feeds images and CameraInfos in
and carries out the :class:`Step` s that come back. Images that wait for their CameraInfo are held (at most
``max_pending``; the oldest falls out failed); once a reference starts, held images older than it fail and
the others are registered in stamp order.
"""

from dataclasses import dataclass

REFERENCE, REGISTER, FAIL, HOLD = 'reference', 'register', 'fail', 'hold'


@dataclass(frozen=True)
class Step:
    """What to do with one image: make it the reference (with ``camera_info``), register it, fail it
    (``reason``), or hold it (nothing yet; the caller may say it waits)."""

    kind: str
    stamp_ns: int
    image: object
    camera_info: object = None
    reason: str = ''


def stamp_text(stamp_ns: int) -> str:
    return f'{stamp_ns // 1_000_000_000}.{stamp_ns % 1_000_000_000:09d}'


class ReferencePairing:
    """One drone's pairing; :attr:`started` once :meth:`started_with` confirmed a reference.

    Args:
        max_pending: images held while waiting for the CameraInfo of their stamp.
        max_camera_infos: CameraInfos kept to pair with later images.
    """

    def __init__(self, max_pending: int = 5, max_camera_infos: int = 50):
        self.max_pending, self.max_camera_infos = max_pending, max_camera_infos
        self.started = False
        self.camera_infos = {}  # stamp_ns -> CameraInfo
        self.pending = {}  # stamp_ns -> image waiting for a CameraInfo

    def camera_info(self, stamp_ns: int, info) -> list:
        """A CameraInfo arrived: the held image of its stamp (if any) may become the reference."""
        if self.started:
            return []
        self.camera_infos[stamp_ns] = info
        while len(self.camera_infos) > self.max_camera_infos:
            self.camera_infos.pop(min(self.camera_infos))
        if stamp_ns in self.pending:
            return [Step(REFERENCE, stamp_ns, self.pending.pop(stamp_ns), info)]
        return []

    def image(self, stamp_ns: int, image) -> list:
        """An image arrived: registered once a reference started, the reference if its CameraInfo is there,
        else held (the oldest held image fails when more than ``max_pending`` wait)."""
        if self.started:
            return [Step(REGISTER, stamp_ns, image)]
        if stamp_ns in self.camera_infos:
            return [Step(REFERENCE, stamp_ns, image, self.camera_infos[stamp_ns])]
        self.pending[stamp_ns] = image
        steps = [Step(HOLD, stamp_ns, image)]
        while len(self.pending) > self.max_pending:
            old = min(self.pending)
            steps.append(
                Step(
                    FAIL,
                    old,
                    self.pending.pop(old),
                    reason=(f'no reference: no CameraInfo with stamp {stamp_text(old)} arrived'),
                )
            )
        return steps

    def started_with(self, stamp_ns: int) -> list:
        """The image of ``stamp_ns`` is now the reference: what becomes of the held images (older: failed,
        newer: registered, in stamp order). A reference that could not be made is simply not confirmed."""
        self.started = True
        self.camera_infos.clear()
        steps = []
        for stamp in sorted(self.pending):
            image = self.pending.pop(stamp)
            steps.append(
                Step(REGISTER, stamp, image)
                if stamp >= stamp_ns
                else Step(FAIL, stamp, image, reason='arrived before the reference image (no CameraInfo of its stamp)')
            )
        return steps
