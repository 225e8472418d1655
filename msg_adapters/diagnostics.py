"""The node's status report as diagnostic_msgs/DiagnosticArray."""

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue

from .stamps import time_msg

OK, WARN, ERROR = DiagnosticStatus.OK, DiagnosticStatus.WARN, DiagnosticStatus.ERROR


def _text(value):
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def diagnostic_array(stamp_ns, name, hardware_id, level, message, values):
    """One status named `name`; `values` is an ordered mapping key -> value."""
    status = DiagnosticStatus(
        level=level,
        name=name,
        message=message,
        hardware_id=hardware_id,
        values=[KeyValue(key=str(k), value=_text(v)) for k, v in values.items()],
    )
    msg = DiagnosticArray(status=[status])
    msg.header.stamp = time_msg(stamp_ns)
    return msg


def diagnostic_values(msg):
    """{key: value-string} of every status in a DiagnosticArray, merged."""
    return {kv.key: kv.value for status in msg.status for kv in status.values}
