"""What one image's calibration says (``matrix_core.calib.drone_calibrator.CalibResult.status``), for every
consumer: the calib node's ``calib/V`` diagnostics (``status`` value), ``matrix-tracker calibrate``'s
``calibration_status.csv`` and the offline calibration sources that read it back (``matrix_core.bev``)."""

import enum


class CalibStatus(enum.Enum):
    """The values are the text form: what the CSV and the diagnostics carry and logs print."""

    OK = 'ok'  # a plausible pose from this image
    STALE = 'stale'  # no plausible pose from this image: the last good one, ``age_s`` old (message: why)
    FAILED = 'failed'  # no pose at all: no prior, or nothing good yet to fall back on (message: why)
    BAD_INPUT = 'bad_input'  # the image could not be used at all (message: why)

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)

    @classmethod
    def from_name(cls, name: str) -> 'CalibStatus':
        """The status whose text form is ``name``; ValueError naming the valid ones."""
        try:
            return cls(str(name))
        except ValueError:
            raise ValueError(f'unknown calibration status {name!r}; one of {", ".join(map(str, cls))}') from None
