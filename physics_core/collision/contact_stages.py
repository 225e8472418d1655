"""The contact stages of one substep as compiled functions (see __init__ for
the order), called by the compiled step loop (physics_core/step_loop.py).

Each stage takes what it reads explicitly: the contact model and
parameters (contact_data.py), the body arrays, the solver's inverse masses,
and what the earlier stages of the same substep made (the rows, the times
of impact, the bounce targets). What outlives a substep is in the warm
cache, the sleep state and the event log's state.
"""
import math

import numpy as np
from numba import njit

from .bounce import add_bounces
from .collision_pass import PASS_COLS, collision_pass
from .contact_build import build_rows, inertia_table
from .contact_data import (CCD_ITERATIONS, CCD_THRESHOLD, CCD_TOLERANCE, CORRECTION_RATE,
                           END_WEIGHT, ITERATIONS, MARGIN, MAX_CORRECTION_SPEED,
                           POSITION_ITERATIONS, RESTING_BLOCK, RESTITUTION_ITERATIONS,
                           RESTITUTION_RAMP, RESTITUTION_THRESHOLD, RULE, SHOCK_ON, SLEEP_ANGULAR,
                           SLEEP_LINEAR, SLEEP_ON, SLEEP_TIME, SLOP, STATIC_SPEED,
                           VELOCITY_TOLERANCE, WARM_FRACTION)
from .contact_layout import BODY_A, BODY_B, DEPTH, ICOL, LAM, NCOL
from .detection import detect_scratch
from .kinetic_drift import kinetic_velocity_change
from .manifold_friction import anchor_friction_out, anchor_rows, anchor_warm_start
from .push_out import correct
from .scratch import take, take_bools, take_int_rows, take_ints, take_rows
from .sequential_impulses import (friction_and_slip, friction_of, least_mass,
                                  solve_velocities, warm_start)
from .shock_propagation import STALL, holds_something, shock_sweep, swept_bodies
from .sleep_islands import _sync, _update, _wake_touched
from .time_of_impact import rewind_fast_bodies
from .warm_cache import warm_clear, warm_load, warm_store

# The shock sweep settles each manifold to this fraction of the sweeps'
# velocity tolerance (a looser stop let the 20-stack's top creep 1.4 mm a
# second), and leaves out groups of bodies whose sweeps met the same
# fraction of their stop.
SETTLE = 0.01


@njit(cache=True, inline="always")
def moving_bodies(is_static, awake, store):
    """(n,) awake and dynamic, in scratch (scratch.py)."""
    out = take_bools(store, len(awake))
    for i in range(len(awake)):
        out[i] = awake[i] and not is_static[i]
    return out


@njit(cache=True)
def solver_masses(cm, awake, inv_mass, inv_inertia):
    """The solver's inverse masses: the model's, zero for sleeping bodies."""
    for i in range(len(awake)):
        w = 1.0 if awake[i] else 0.0
        inv_mass[i] = cm.inv_mass[i] * w
        for j in range(3):
            inv_inertia[i, j] = cm.inv_inertia[i, j] * w


@njit(cache=True, inline="always")
def ccd_stage(cm, fp, ip, pos, quat, omega, awake, p0, q0, toi, store):
    moving = moving_bodies(cm.is_static, awake, store)
    return rewind_fast_bodies(cm.kind, cm.dims, cm.reach, cm.is_static, moving, p0, q0, pos, quat,
                              omega, fp[CCD_THRESHOLD], fp[MARGIN], ip[CCD_ITERATIONS],
                              fp[CCD_TOLERANCE], toi, take_bools(store, len(pos)))


@njit(cache=True, inline="always")
def kept_rows(moving, a, b, keep):
    """Indices of the contacts with a moving body (a static–sleeping pair
    rests), written into `keep` (at least len(a) long)."""
    k = 0
    for c in range(len(a)):
        if moving[a[c]] or moving[b[c]]:
            keep[k] = c
            k += 1
    return keep[:k]


@njit(cache=True, inline="always")
def detect_stage(cm, fp, ip, pos, quat, awake, sleep, cap, store):
    """Contacts at the end-of-substep poses, sleeping bodies touched by a moving
    one woken (their islands too): (a, b, point, normal, depth, key, rows
    computed, woke)."""
    timer, island, prev_awake, next_island = sleep
    if ip[SLEEP_ON]:
        _sync(awake, timer, island, prev_awake)
    (a, b, point, normal, depth, key), k = detect_scratch(cm.kind, cm.dims, cm.is_static, cm.reach,
                                                          pos, quat, fp[MARGIN], cap, store)
    woke = False
    if ip[SLEEP_ON] and len(a):
        woke = _wake_touched(awake, cm.is_static, a, b, fp[SLEEP_TIME], timer, island,
                             prev_awake)
    keep = kept_rows(moving_bodies(cm.is_static, awake, store), a, b,
                     take_ints(store, len(a)))
    if len(keep) < len(a):
        a, b, point, normal = a[keep], b[keep], point[keep], normal[keep]
        depth, key = depth[keep], key[keep]
    return a, b, point, normal, depth, key, k, woke


@njit(cache=True, inline="always")
def rows_stage(cm, fp, ip, contacts, pos, quat, vel, omega, inv_mass, inv_inertia, warm, toi, h,
               v0, w0, store):
    """The contact rows (R, I) of the detected contacts, their impulses loaded
    from the warm cache (applied by restitution_stage), and the manifolds'
    friction anchors (M, MI) (manifold_friction.py); v0, w0 the
    start-of-substep velocities (a new contact's friction regime)."""
    a, b, point, normal, depth, key = contacts
    R, I = take_rows(store, len(a), NCOL), take_int_rows(store, len(a), ICOL)
    iw = inertia_table(a, b, quat, inv_inertia, store)
    build_rows(R, I, a, b, point, normal, depth, pos, iw, vel, omega, inv_mass, cm.material,
               cm.mu_static, cm.mu_kinetic, cm.restitution, ip[RULE], h, toi)
    warm_load(R, I, key, warm[0], warm[1], fp[WARM_FRACTION], fp[STATIC_SPEED], v0, w0)
    M, MI = anchor_rows(R, I, point, pos, iw, toi, h, store)
    return R, I, M, MI


@njit(cache=True, inline="always")
def restitution_stage(fp, ip, R, I, M, MI, vel, omega, v0, w0, h, store):
    """The collision pass (bounce.py) on the velocities the integrator gave,
    v0, w0 the start-of-substep ones: (target, τ, J) of every contact; then
    the warm start (the rows' loaded impulses applied). The correct stage
    moves positions by the velocity change from here on, warm start
    included. The pass comes first because whether a contact bounces is
    decided by its approach speed at the impact (COURSE.md 5, coefficient
    of restitution), and the warm start is not an impact: it is last
    substep's solve applied ahead of this one's, and where that solve had
    not converged (a tall pyramid's eight sweeps) or the shock sweep changed
    its outcome, it moves loaded bodies against each other until this
    substep's sweeps balance it. Taken by the pass for approaches, those
    moves bounced boxes inside standing pyramids: pyramids of 66 to 300
    boxes spread 3 to 12 cm in their first second and kept spreading
    (tests/test_stacks_and_mass_ratios.py); the pyramid of 10, 1.7 mm."""
    k = len(R)
    target, tau, J = take(store, k), take(store, k), take_rows(store, k, 3)
    collision_pass(R, I, vel, omega, v0, w0, fp[RESTITUTION_THRESHOLD], fp[RESTITUTION_RAMP], h,
                   fp[END_WEIGHT], ip[RESTITUTION_ITERATIONS], target, tau, J,
                   take_rows(store, k, PASS_COLS), take_ints(store, len(vel) + 1), (M, MI))
    if k and fp[WARM_FRACTION] > 0.0:
        warm_start(R, I, vel, omega)
        anchor_warm_start(M, MI, I, vel, omega)
    return target, tau, J


@njit(cache=True, inline="always")
def solve_stage(fp, ip, R, I, M, MI, key, vel, omega, warm, J, masses, store):
    """Sequential-impulse sweeps (the rows come warm-started), the solve's
    impulses kept in the warm cache, then the shock-propagation sweep
    (shock_propagation.py) and the collision pass's J added to λ. Returns
    the friction impulses (world vectors, for the events), the sweeps done
    and the velocity change of friction at its kinetic bound (kinetic_drift.py)."""
    if len(R) == 0:
        warm_clear(warm[0], warm[1])
        return take_rows(store, 0, 3), 0, take_rows(store, 0, 3)
    # an impulse change dλ moves a row's relative velocity by about dλ / m_eff
    limit = fp[VELOCITY_TOLERANCE] * least_mass(R) if fp[VELOCITY_TOLERANCE] > 0.0 else -1.0
    changes = take(store, len(MI))
    # the shock sweep leaves out a group whose manifolds all changed by less
    # than `left_out` in the last sweep (below); where it will run, sweeps
    # converging fast go on to that bound, and sweeps that stall stop
    # (solve_velocities): it settles what they leave. With nothing immovable
    # it visits nothing, and the sweeps stop as with it off
    left_out = SETTLE * limit
    shock = ip[SHOCK_ON] and holds_something(R)
    stops = (limit, left_out, STALL) if shock else (limit, limit, math.inf)
    sweeps, _ = solve_velocities(R, I, M, MI, vel, omega, ip[ITERATIONS], stops, changes,
                                 take(store, len(R)))
    friction, slip = take_rows(store, len(R), 3), take(store, len(R))
    friction_and_slip(R, I, vel, omega, friction, slip)
    anchor_friction_out(R, M, MI, friction)
    warm_store(warm[0], warm[1], key, R, friction, slip)
    # a group of bodies whose manifolds all ended their last sweep changing no
    # impulse by SETTLE of the sweeps' stop (no contact-point velocity by
    # `settle`) leaves the shock sweep nothing to remove
    # (tests/test_shock_skip.py): the sweep leaves it out, and is not run
    # when no group is left. A resting body's warm start meets this in one
    # sweep (a resting ball's step 4.2 -> 3.1 us); a stack converging slowly
    # never does
    settle = SETTLE * fp[VELOCITY_TOLERANCE]
    if ip[SHOCK_ON]:
        visited, layer = shock_sweep(R, I, M, MI, vel, omega, len(vel), ip[SHOCK_ON], settle,
                                     masses, ip[RESTING_BLOCK] != 0, (changes, left_out),
                                     store)
        if visited:
            friction_of(R, I, friction, swept_bodies(layer, store))
            anchor_friction_out(R, M, MI, friction)
    slide = kinetic_velocity_change(R, I, M, MI, len(vel), store)
    add_bounces(R, J, friction)
    return friction, sweeps, slide


@njit(cache=True, inline="always")
def correct_stage(fp, ip, R, I, pos, quat, vel, omega, vel0, omega0, target, tau, toi, slide, h,
                  store):
    correct(R, I, pos, quat, vel, omega, vel0, omega0, target, tau, toi, slide, h, fp[SLOP],
            fp[CORRECTION_RATE], fp[MAX_CORRECTION_SPEED], ip[POSITION_ITERATIONS], store)


@njit(cache=True)
def touching_edges(R, I):
    """(a, b) of the contacts that touch (overlap or push): the sleep islands' edges."""
    keep = np.empty(len(R), np.int64)
    k = 0
    for c in range(len(R)):
        if R[c, DEPTH] >= 0.0 or R[c, LAM] > 0.0:
            keep[k] = c
            k += 1
    return I[keep[:k], BODY_A].copy(), I[keep[:k], BODY_B].copy()


@njit(cache=True)
def unsettled_bodies(R, I, n, slop):
    """Bodies in a contact deeper than twice the slop: position correction is
    still pushing them apart, so they are not at rest whatever their velocity
    (a resting contact sits at the slop, plus the sag of one substep of
    gravity, g h², when it is detected)."""
    out = np.zeros(n, np.bool_)
    for c in range(len(R)):
        if R[c, DEPTH] > 2.0 * slop:
            out[I[c, BODY_A]] = True
            out[I[c, BODY_B]] = True
    return out


@njit(cache=True)
def sleep_stage(cm, fp, R, I, awake, vel, omega, sleep, dt):
    """Rest timers, and islands at rest put to sleep; True when some body slept."""
    timer, island, prev_awake, next_island = sleep
    ea, eb = touching_edges(R, I)
    unsettled = unsettled_bodies(R, I, len(awake), fp[SLOP])
    return _update(awake, cm.is_static, vel, omega, unsettled, ea, eb, dt, fp[SLEEP_LINEAR],
                   fp[SLEEP_ANGULAR], fp[SLEEP_TIME], timer, island, prev_awake, next_island)
