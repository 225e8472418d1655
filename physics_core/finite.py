"""The finite check after every stage: a NaN or inf is caught at the end of
the stage that made it, never carried into the next (MuJoCo checks its
state at stage boundaries the same way). A component beyond STATE_LIMIT
(command_limits.py) counts as non-finite too: it is finite for float64 but
not for the broad phase's integer grid cells."""
import numpy as np
from numba import njit

from .command_limits import STATE_LIMIT


@njit(cache=True, inline="always")
def _outside(x):
    """Whether x is NaN, ±inf or beyond STATE_LIMIT (abs(NaN) <= STATE_LIMIT is False)."""
    return not (abs(x) <= STATE_LIMIT)


@njit(cache=True)
def _row_finite(a, i):
    for j in range(a.shape[1]):
        if _outside(a[i, j]):
            return False
    return True


@njit(cache=True, inline="always")
def _any_outside(a):
    """Whether some entry of the C-contiguous array a is outside, in one pass
    over its flat entries with no early exit: the compiler vectorises it.
    The same answer as a row-by-row search that stops at the first bad
    entry, which it cannot vectorise: 9.5 against 1.3 µs on 1,000 bodies'
    pose and velocity, 50 against 11 ns on one body."""
    bad = False
    for k in range(a.size):
        bad |= _outside(a.flat[k])
    return bad


@njit(cache=True, inline="always")
def all_finite(pos, quat, vel, omega):
    """Whether every body's pose and velocity is finite (allocates nothing: it
    runs after every stage)."""
    return not (_any_outside(pos) | _any_outside(vel) | _any_outside(omega) | _any_outside(quat))


@njit(cache=True, inline="always")
def velocities_finite(vel, omega):
    """all_finite for a stage that changes velocities only (the poses were
    checked after the stage that last moved them)."""
    return not (_any_outside(vel) | _any_outside(omega))


@njit(cache=True)
def non_finite_bodies(pos, quat, vel, omega):
    """Indices of the bodies with a NaN or inf in their pose or velocity."""
    bad = np.zeros(len(pos), np.bool_)
    count = 0
    for i in range(len(pos)):
        if not (_row_finite(pos, i) and _row_finite(vel, i) and _row_finite(omega, i)
                and _row_finite(quat, i)):
            bad[i] = True
            count += 1
    out = np.empty(count, np.int64)
    k = 0
    for i in range(len(pos)):
        if bad[i]:
            out[k] = i
            k += 1
    return out
