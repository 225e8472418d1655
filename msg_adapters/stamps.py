"""Simulation time as integer nanoseconds and as builtin_interfaces/Time."""

from builtin_interfaces.msg import Time

NS_PER_S = 1_000_000_000


def sim_time_ns(seconds):
    """Sim seconds (float) to the nearest integer nanosecond."""
    return int(round(float(seconds) * NS_PER_S))


def time_msg(ns):
    """Integer nanoseconds to builtin_interfaces/Time."""
    sec, nanosec = divmod(int(ns), NS_PER_S)
    return Time(sec=sec, nanosec=nanosec)


def time_ns(msg):
    """builtin_interfaces/Time to integer nanoseconds."""
    return int(msg.sec) * NS_PER_S + int(msg.nanosec)
