"""Largest loads a command may carry, and the largest state the step accepts.

A force of 1e300 N is finite, but a step or two later the body's position
overflows what the broad phase can turn into grid cells (and a held torque
of 1e300 N·m spins a quaternion into NaN). Commands beyond these bounds are
refused with CommandError before they touch the state; the node drops them
as `out_of_range` (physics_node/commands.py). The bounds are far beyond any
physical load on a body this engine simulates (a Saturn V first stage makes
3.5e7 N), and far inside what float64 carries through the step.
"""
import numpy as np

MAX_FORCE = 1e9             # N, |F| of a held force
MAX_TORQUE = 1e9            # N·m, |τ| of a held torque
MAX_IMPULSE = 1e7           # N·s, |J| of one impulse
MAX_ANGULAR_IMPULSE = 1e7   # N·m·s, |L| of one angular impulse
MAX_POINT_DISTANCE = 1e6    # m, |p - body position| of a force's or impulse's point

# The finite check after every stage (finite.py) also refuses a position,
# velocity or angular velocity component beyond this: the broad phase maps a
# position to int64 grid cells (|x| / cell must stay well below 9.2e18 for
# cells down to 1 mm), and the contact stages square velocities. A body that
# gets there is named in NonFiniteStateError like a NaN one.
STATE_LIMIT = 1e15          # m, m/s, rad/s per component


def magnitude(v) -> float:
    """|v| without overflow (1e300 components give 1.7e300, not inf); NaN stays NaN."""
    v = np.asarray(v, dtype=float)
    scale = float(np.max(np.abs(v))) if v.size else 0.0
    if not np.isfinite(scale) or scale == 0.0:
        return scale
    return scale * float(np.sqrt(np.sum((v / scale) ** 2)))
