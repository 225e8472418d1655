"""What the compiled contact stages share, packed into a few tuples (a jitted
call pays per argument, and a loop over steps in compiled code passes them
along for nothing).

- `ContactModel`: the frozen per-body data the stages read (shape,
  material, restitution, the model's inverse masses) and the friction table.
- `ContactParams` as two arrays: floats `fp` and integers `ip`, indexed by
  the names below (the `effects.contacts` keys of contact_params.py).
- the warm-start cache in numba typed lists, so compiled code can replace
  its arrays as the contact set changes and the change stays with the
  World; the sleep timers (fixed size) as plain arrays.
"""
from collections import namedtuple

import numpy as np
from numba import njit
from numba.typed import List

from .contact_build import RESTITUTION_RULES
from .geometry import Geometry

ContactModel = namedtuple("ContactModel", "kind dims is_static reach material restitution "
                                          "inv_mass inv_inertia mu_static mu_kinetic")

# float parameters (fp)
(MARGIN, STATIC_SPEED, WARM_FRACTION, VELOCITY_TOLERANCE, RESTITUTION_THRESHOLD,
 RESTITUTION_RAMP, SLOP, CORRECTION_RATE, MAX_CORRECTION_SPEED, CCD_THRESHOLD, CCD_TOLERANCE,
 SLEEP_LINEAR, SLEEP_ANGULAR, SLEEP_TIME, END_WEIGHT, N_FP) = range(16)
# END_WEIGHT: the share of the end-of-substep velocity in the integrator's
# displacement over a substep (INTEGRATOR_END_WEIGHT), for the time of impact
INTEGRATOR_END_WEIGHT = {"explicit_euler": 0.0, "semi_implicit_euler": 1.0,
                         "velocity_verlet": 0.5, "rk4": 0.5, "adaptive": 0.5}
# integer parameters (ip)
(ITERATIONS, POSITION_ITERATIONS, CCD_ITERATIONS, CCD_ON, SLEEP_ON, RULE, RESTITUTION_ITERATIONS,
 SHOCK_ON, RESTING_BLOCK, N_IP) = range(10)

# ip[SHOCK_ON]: updates of one manifold at most in the shock-propagation sweep
# (shock_propagation.py); a box on four corners needed 16 to stop tilting
# (4 passes let a 20-box stack rock and fall)
SETTLE_PASSES = 16

# the warm-start cache: per contact seen last substep, its key and (normal
# impulse, friction impulse x y z, slip speed), ascending keys (warm_cache.py)
WARM_NORMAL, WARM_FRICTION, WARM_SLIP, WARM_COLS = 0, 1, 4, 5


def contact_model(model) -> ContactModel:
    g = Geometry.from_model(model)
    return ContactModel(g.kind, g.dims, g.is_static, g.reach,
                        np.ascontiguousarray(model.material, dtype=np.int64),
                        np.ascontiguousarray(model.restitution, dtype=np.float64),
                        np.ascontiguousarray(model.inv_mass, dtype=np.float64),
                        np.ascontiguousarray(model.inv_inertia, dtype=np.float64),
                        np.ascontiguousarray(model.mu_static, dtype=np.float64),
                        np.ascontiguousarray(model.mu_kinetic, dtype=np.float64))


def contact_params(p, integrator="semi_implicit_euler"):
    """(fp, ip) arrays of a contact_params.ContactParams, for a scene integrated
    by `integrator`."""
    fp = np.empty(N_FP)
    fp[END_WEIGHT] = INTEGRATOR_END_WEIGHT[integrator]
    fp[[MARGIN, STATIC_SPEED, WARM_FRACTION, VELOCITY_TOLERANCE, RESTITUTION_THRESHOLD,
        RESTITUTION_RAMP, SLOP, CORRECTION_RATE, MAX_CORRECTION_SPEED, CCD_THRESHOLD,
        CCD_TOLERANCE, SLEEP_LINEAR, SLEEP_ANGULAR, SLEEP_TIME]] = (
        p.margin, p.static_friction_speed, p.warm_start, p.velocity_tolerance,
        p.restitution_threshold, p.restitution_ramp, p.slop, p.correction_rate,
        p.max_correction_speed, p.ccd_threshold, p.ccd_tolerance, p.sleep_linear_speed,
        p.sleep_angular_speed, p.sleep_time)
    ip = np.empty(N_IP, np.int64)
    ip[[ITERATIONS, POSITION_ITERATIONS, CCD_ITERATIONS, CCD_ON, SLEEP_ON, RULE,
        RESTITUTION_ITERATIONS, SHOCK_ON, RESTING_BLOCK]] = (
        p.iterations, p.position_iterations, p.ccd_iterations, int(p.ccd), int(p.sleep),
        RESTITUTION_RULES[p.restitution_combine], p.restitution_iterations,
        SETTLE_PASSES if p.shock_propagation else 0, int(p.resting_block))
    return fp, ip


@njit(cache=True)
def new_warm_cache():
    """(keys, values): typed lists of one array each, so compiled code can
    replace the arrays (the contact set grows) and the World keeps them.
    keys[0][0] is the number of contacts kept, their ascending keys follow;
    values[0] has their values in its first rows (warm_cache.warm_store
    fills them in place, growing the arrays by doubling). Built in compiled
    code: typed-list methods compiled from Python are not cached, and
    compiling them took about 1 s of every `import physics_core`."""
    keys = List()
    values = List()
    keys.append(np.zeros(1, np.int64))
    values.append(np.zeros((0, WARM_COLS)))
    return keys, values


def new_sleep_state(n):
    """(timer, island, prev_awake, next_island) of sleep_islands.py."""
    return (np.zeros(n), np.full(n, -1, np.int64), np.ones(n, np.bool_), np.zeros(1, np.int64))
