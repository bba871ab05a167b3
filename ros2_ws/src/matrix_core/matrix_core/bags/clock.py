"""The sequence clock: the header stamp of frame ``i`` is ``start_time + i * frame_period`` seconds.

The one place that knows the default clock (first stamp 1.0 s, so that no frame has the zero stamp that ROS
reads as "unset"; 0.5 s per frame, the MATRIX rate of 2 Hz) and how a bag stores it:
:class:`~matrix_core.bags.writer.SequenceBagWriter` writes it into the bag's ``metadata.yaml`` as rosbag2
custom data (``ros2 bag info`` lists it)::

    rosbag2_bagfile_information:
      custom_data:
        matrix_tracker.start_time: '1.0'
        matrix_tracker.frame_period: '0.5'

:func:`read_sequence_clock` reads it back (bag player, recorder, ``matrix-tracker evaluate-recording``);
bags written before the clock was stored get the default clock, with a logged note.
"""

import logging
import math
from dataclasses import dataclass, replace
from pathlib import Path

import yaml

START_TIME_KEY = 'matrix_tracker.start_time'
FRAME_PERIOD_KEY = 'matrix_tracker.frame_period'

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SequenceClock:
    """Stamps of a sequence: frame ``i`` at ``start_time + i * frame_period`` seconds."""

    start_time: float = 1.0
    frame_period: float = 0.5

    def __post_init__(self):
        if not (math.isfinite(self.start_time) and math.isfinite(self.frame_period) and self.frame_period > 0):
            raise ValueError(f'a sequence clock needs a finite start_time and a positive frame_period, got {self}')

    def stamp(self, index: int) -> float:
        """Header stamp (seconds) of frame ``index``."""
        return self.start_time + index * self.frame_period

    def stamp_ns(self, index: int) -> int:
        """Header stamp (nanoseconds) of frame ``index``."""
        return int(round(self.stamp(index) * 1e9))

    def frame(self, stamp: float) -> int:
        """Frame index of a stamp in seconds (the nearest frame: stamps may carry rounding)."""
        return int(round((stamp - self.start_time) / self.frame_period))

    def frame_ns(self, stamp_ns: int) -> int:
        """Frame index of a stamp in nanoseconds."""
        return self.frame(stamp_ns * 1e-9)

    def overridden(self, start_time: float = None, frame_period: float = None) -> 'SequenceClock':
        """This clock with the values that are given (not None, not NaN) replaced."""
        given = {
            k: float(v)
            for k, v in (('start_time', start_time), ('frame_period', frame_period))
            if v is not None and not math.isnan(v)
        }
        return replace(self, **given)

    def custom_data(self) -> dict:
        """The rosbag2 custom-data entries (strings) that store this clock."""
        return {START_TIME_KEY: repr(float(self.start_time)), FRAME_PERIOD_KEY: repr(float(self.frame_period))}

    def describe(self) -> str:
        return f'first stamp {self.start_time:g} s, {self.frame_period:g} s per frame'


DEFAULT_CLOCK = SequenceClock()


def stored_sequence_clock(bag_path):
    """The clock stored in a bag folder's ``metadata.yaml``, or None when it has none (older bags, bags of
    other tools). Raises FileNotFoundError when ``bag_path`` has no ``metadata.yaml``, ValueError when the
    stored values are not a valid clock."""
    meta_path = Path(bag_path) / 'metadata.yaml'
    if not meta_path.is_file():
        raise FileNotFoundError(f'{bag_path}: not a rosbag2 folder (no metadata.yaml)')
    info = (yaml.safe_load(meta_path.read_text()) or {}).get('rosbag2_bagfile_information') or {}
    custom = info.get('custom_data') or {}
    if START_TIME_KEY not in custom or FRAME_PERIOD_KEY not in custom:
        return None
    try:
        return SequenceClock(float(custom[START_TIME_KEY]), float(custom[FRAME_PERIOD_KEY]))
    except ValueError as exc:
        raise ValueError(f'{meta_path}: invalid sequence clock in custom_data: {exc}') from None


def read_sequence_clock(bag_path, note=None) -> SequenceClock:
    """The clock of a sequence bag: the stored one, else (bags written before it was stored) the default,
    with a note to ``note`` (a callable taking the text, e.g. a ROS node's logger; default: this module's
    logging warning)."""
    clock = stored_sequence_clock(bag_path)
    if clock is None:
        clock = DEFAULT_CLOCK
        (note or _log.warning)(
            f'{bag_path} stores no sequence clock (written before it was stored): assuming {clock.describe()}'
        )
    return clock
