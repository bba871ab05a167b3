"""diagnostic_msgs builders shared by the nodes: one ``DiagnosticStatus`` per drone and frame, named
``<node>/<view>`` (what ``graph_monitor`` counts as processed), stamped with the frame's stamp."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from std_msgs.msg import Header

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR
MESSAGE_CHARS = 250  # keep a status readable in rqt / `ros2 topic echo`


def status(name: str, level, message: str, values=(), hardware_id: str = '') -> DiagnosticStatus:
    """A DiagnosticStatus; ``values`` is a dict or (key, value) pairs (values shown with ``str``)."""
    pairs = values.items() if isinstance(values, dict) else values
    return DiagnosticStatus(
        level=level,
        name=name,
        message=message[:MESSAGE_CHARS],
        hardware_id=hardware_id,
        values=[KeyValue(key=k, value=str(v)) for k, v in pairs],
    )


def array(header_or_stamp, *statuses: DiagnosticStatus) -> DiagnosticArray:
    """A DiagnosticArray of ``statuses``; a bare stamp becomes its header."""
    header = header_or_stamp if isinstance(header_or_stamp, Header) else Header(stamp=header_or_stamp)
    return DiagnosticArray(header=header, status=list(statuses))
