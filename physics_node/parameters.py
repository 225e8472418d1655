"""The node's ROS parameters: names, defaults, checks."""

from dataclasses import dataclass

from rcl_interfaces.msg import ParameterDescriptor

# name: (default, description, changeable while running)
PARAMETERS = {
    "scene": ("", "scene YAML path; empty = the built-in default scene", False),
    "real_time_factor": (1.0, "sim seconds per wall second; 0 = as fast as possible", True),
    "record": ("", "MCAP file to record the session to; empty = no recording", False),
    "duration": (0.0, "sim seconds to run, then exit; 0 = until stopped", False),
    "publish_every": (1, "publish poses, odometry, contacts and markers every N steps", True),
    "paused": (False, "start (or hold) the simulation paused", True),
    "command_timeout": (0.0, "sim seconds a wrench is held; 0 = until replaced", True),
    "odometry": (
        "subscribed",
        "per-body ~/<body>/odom: 'subscribed' = only to topics someone listens to, 'all' = every body",
        True,
    ),
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


def _as_float(name, value):
    # `-p real_time_factor:=0` arrives as an integer; accept any real number.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterValueError(f"parameter {name!r} must be a number, got {value!r}")
    return float(value)


def coerce(name, value):
    """Check and normalise one parameter value; raises ParameterValueError."""
    if name in ("scene", "record"):
        if not isinstance(value, str):
            raise ParameterValueError(f"parameter {name!r} must be a string path, got {value!r}")
        return value
    if name in ("real_time_factor", "duration", "command_timeout"):
        v = _as_float(name, value)
        if not v >= 0.0:
            raise ParameterValueError(f"parameter {name!r} must be >= 0, got {value!r}")
        return v
    if name == "publish_every":
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ParameterValueError(f"parameter 'publish_every' must be an integer >= 1, got {value!r}")
        return value
    if name == "odometry":
        if value not in ODOMETRY_MODES:
            raise ParameterValueError(
                f"parameter 'odometry' must be one of {', '.join(ODOMETRY_MODES)}, got {value!r}"
            )
        return value
    if name == "paused":
        if not isinstance(value, bool):
            raise ParameterValueError(f"parameter 'paused' must be true or false, got {value!r}")
        return value
    raise ParameterValueError(f"unknown parameter {name!r}")


def declare(node):
    """Declare every parameter on `node` and return the checked Settings."""
    values = {}
    for name, (default, description, changeable) in PARAMETERS.items():
        descriptor = ParameterDescriptor(description=description, read_only=not changeable, dynamic_typing=True)
        param = node.declare_parameter(name, default, descriptor)
        values[name] = coerce(name, param.value)
    return Settings(**values)
