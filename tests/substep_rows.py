"""One contact substep of a World rebuilt by hand up to the collision pass
or the solve: gravity for one substep, detection, the rows (and the
collision pass), as contact_substep runs them (for tests of the pass and
of the solve's later passes)."""
import numpy as np

from physics_core.collision import contact_stages as CS
from physics_core.collision.contact_data import ITERATIONS, VELOCITY_TOLERANCE
from physics_core.collision.scratch import new_counts
from physics_core.collision.sequential_impulses import least_mass, solve_velocities
from physics_core.collision.shock_propagation import STALL


def rows_before_pass(w, dt, g=0.0):
    """((R, I, M, MI), vel, omega, quat, store) of w's next substep of length
    dt under gravity g (m/s², along −z): the rows before the collision pass,
    and what the pass reads besides them."""
    cs, s = w.contact_system, w.state
    cm, fp, ip = cs.cm, cs.fp, cs.ip
    store = (np.empty(1 << 18), new_counts(), np.empty(0))
    pos, quat, vel, omega = s.pos.copy(), s.quat.copy(), s.vel.copy(), s.omega.copy()
    moving = cm.inv_mass > 0
    vel[:, 2] -= g * dt * moving
    pos += vel * dt * moving[:, None]
    a, b, point, normal, depth, key, _, _ = CS.detect_stage(cm, fp, ip, pos, quat, s.awake,
                                                            cs.sleep, cs.cap[0], store)
    contacts = tuple(np.array(x) for x in (a, b, point, normal, depth, key))
    rows = CS.rows_stage(cm, fp, ip, contacts, pos, quat, vel, omega, w._inv_mass,
                         w.inv_inertia, cs.warm, np.full(len(pos), -1.0), dt, s.vel.copy(),
                         s.omega.copy(), store)
    return tuple(np.array(x) for x in rows), vel, omega, quat, store


def pass_applied(w, dt, g=9.81):
    """((R, I, M, MI), vel, omega, quat, store, (target, tau, J)) of w's next
    substep of length dt: the rows and velocities after the collision pass
    (and the warm start), and the pass's bounce targets, times of impact
    and impulses J (k, 3: normal, t1, t2)."""
    (R, I, M, MI), vel, omega, quat, store = rows_before_pass(w, dt, g)
    s, cs = w.state, w.contact_system
    made = CS.restitution_stage(cs.fp, cs.ip, R, I, M, MI, vel, omega, s.vel.copy(),
                                s.omega.copy(), dt, store)
    return (R, I, M, MI), vel, omega, quat, store, tuple(np.array(x) for x in made)


def rows_before_solve(w, dt, g=9.81):
    """(R, I, M, MI, vel, omega, quat, store) of w's next substep of length
    dt, the collision pass applied: what the sweeps start from."""
    (R, I, M, MI), vel, omega, quat, store, _ = pass_applied(w, dt, g)
    return R, I, M, MI, vel, omega, quat, store


def rows_after_sweeps(w, dt, g=9.81):
    """(R, I, M, MI, vel, omega, quat, store, changes, bound) of w's next
    substep of length dt: the rows solved by the sequential-impulse sweeps
    as solve_stage runs them before the shock sweep; changes: each
    manifold's change in the last sweep, bound: the shock sweep's leave-out
    bound (a group whose changes are all below it is left out)."""
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, dt, g)
    cs = w.contact_system
    limit = cs.fp[VELOCITY_TOLERANCE] * least_mass(R)
    changes = np.empty(len(MI))
    solve_velocities(R, I, M, MI, vel, omega, cs.ip[ITERATIONS], (limit, CS.SETTLE * limit, STALL),
                     changes)
    return R, I, M, MI, vel, omega, quat, store, changes, CS.SETTLE * limit
