"""The node's ROS parameters: names, defaults, ranges, checks.

Every number has a range, declared in its ParameterDescriptor
(`floating_point_range` / `integer_range`, so `ros2 param describe` shows
it) and checked by `coerce`, which the node's set-parameters callback and
the command-line flags (main.py) both call: a value outside is refused with
the reason, at start (exit status 2) and at run time (the node runs on).
"""

import math
from dataclasses import dataclass

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from .body_topics import ON_DEMAND_ABOVE

# name: (default, description, changeable while running)
PARAMETERS = {
    "scene": ("", "scene YAML path; empty = the built-in default scene", False),
    "real_time_factor": (1.0, "sim seconds per wall second; 0 = as fast as possible", True),
    "record": (
        "",
        "MCAP file to record the session to; empty = no recording. Set while running: the recording so far is "
        "closed and this file started (empty: recording stops)",
        True,
    ),
    "duration": (0.0, "sim seconds to run, then exit; 0 = until stopped", False),
    "publish_every": (1, "publish poses, odometry, contacts and markers every N steps", True),
    "paused": (False, "start (or hold) the simulation paused", True),
    "command_timeout": (0.0, "sim seconds a wrench is held; 0 = until replaced", True),
    "odometry": (
        "subscribed",
        "per-body ~/<body>/odom: 'subscribed' = only to topics someone listens to, 'all' = every body",
        True,
    ),
    "max_bodies": (10_000, "most bodies a scene file may declare (physics_core/scene_limits.py)", False),
    "topics_on_demand_above": (
        ON_DEMAND_ABOVE,
        "a world of more bodies at start makes each body's wrench, impulse and odom topics only once a peer "
        "publishes or subscribes there (physics_node/body_topics.py); 0 = always on demand",
        False,
    ),
}

# Closed ranges of the numeric parameters. A real-time factor above 1,000 is
# beyond any pacing the step timer can keep (its tick is 2 ms at the least)
# and 1e308 overflowed the pacer; a duration beyond 1e9 s (31 years) or a
# command timeout beyond 1e6 s is a typo, not a plan.
RANGES = {
    "real_time_factor": (0.0, 1000.0),
    "duration": (0.0, 1e9),
    "command_timeout": (0.0, 1e6),
    "publish_every": (1, 1_000_000),
    "max_bodies": (1, 1_000_000),
    "topics_on_demand_above": (0, 1_000_000),
}

# Each Publisher.publish costs 5-10 us in the middleware even with no reader
# (rmw_fastrtps, this machine): one odometry topic per body at 1,000 bodies
# would cost more than a 240 Hz step. 'subscribed' publishes a body's
# odometry while its topic has a subscriber; 'all' publishes every body's.
ODOMETRY_MODES = ("subscribed", "all")


class ParameterValueError(ValueError):
    pass


@dataclass
class Settings:
    scene: str = ""
    real_time_factor: float = 1.0
    record: str = ""
    duration: float = 0.0
    publish_every: int = 1
    paused: bool = False
    command_timeout: float = 0.0
    odometry: str = "subscribed"
    max_bodies: int = 10_000
    topics_on_demand_above: int = ON_DEMAND_ABOVE


def _in_range(name, value, shown):
    low, high = RANGES[name]
    if not low <= value <= high:  # False for NaN
        raise ParameterValueError(f"parameter {name!r} must be between {low:g} and {high:g}, got {shown}")
    return value


def _as_float(name, value):
    # `-p real_time_factor:=0` arrives as an integer; accept any real number.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterValueError(f"parameter {name!r} must be a number, got {str(value)[:80]!r}")
    try:
        v = float(value)
    except OverflowError:  # an integer beyond float64
        v = math.inf
    return _in_range(name, v, f"{value!r}"[:80])


def _as_int(name, value):
    if isinstance(value, bool) or not isinstance(value, int):
        raise ParameterValueError(f"parameter {name!r} must be an integer, got {str(value)[:80]!r}")
    return _in_range(name, value, f"{value!r}"[:80])


def coerce(name, value):
    """Check and normalise one parameter value; raises ParameterValueError."""
    if name in ("scene", "record"):
        if not isinstance(value, str):
            raise ParameterValueError(f"parameter {name!r} must be a string path, got {str(value)[:80]!r}")
        if "\0" in value:
            raise ParameterValueError(f"parameter {name!r} must be a path without NUL characters")
        return value
    if name in ("real_time_factor", "duration", "command_timeout"):
        return _as_float(name, value)
    if name in ("publish_every", "max_bodies", "topics_on_demand_above"):
        return _as_int(name, value)
    if name == "odometry":
        if value not in ODOMETRY_MODES:
            raise ParameterValueError(
                f"parameter 'odometry' must be one of {', '.join(ODOMETRY_MODES)}, got {str(value)[:80]!r}"
            )
        return value
    if name == "paused":
        if not isinstance(value, bool):
            raise ParameterValueError(f"parameter 'paused' must be true or false, got {str(value)[:80]!r}")
        return value
    raise ParameterValueError(f"unknown parameter {name!r}")


def descriptor(name):
    """The ParameterDescriptor of `name`, with its range if it has one."""
    _default, description, changeable = PARAMETERS[name]
    d = ParameterDescriptor(description=description, read_only=not changeable)
    if name in RANGES:
        low, high = RANGES[name]
        if isinstance(low, int) and isinstance(high, int):
            d.integer_range = [IntegerRange(from_value=low, to_value=high, step=1)]
        else:
            d.floating_point_range = [FloatingPointRange(from_value=low, to_value=high, step=0.0)]
            # `-p real_time_factor:=0` arrives as an integer: the type may change,
            # and coerce() checks the range whatever the type.
            d.dynamic_typing = True
    else:
        d.dynamic_typing = True
    return d


def declare(node):
    """Declare every parameter on `node` and return the checked Settings."""
    values = {}
    for name, (default, _description, _changeable) in PARAMETERS.items():
        param = node.declare_parameter(name, default, descriptor(name))
        values[name] = coerce(name, param.value)
    return Settings(**values)
