"""All the contact stages of one substep in one compiled call (COURSE.md 5),
each followed by the finite check and timed, check included.

Stage order: ccd, collide (rows, warm start), restitution (the collision
pass, bounce.py), solve, correct, events, and sleep on the step's last
substep (see __init__). `run` returns -1, or the index of the stage after which some body's state was not
finite (the caller names it and the bodies).
"""
from numba import njit

from ..borrowed import borrow, keep_alive
from ..cycle_clock import lap
from ..finite import all_finite, velocities_finite
from .contact_data import (CCD_ITERATIONS, CCD_ON, CCD_THRESHOLD, CCD_TOLERANCE, MARGIN,
                           SLEEP_ON)
from .contact_layout import LAM, U0
from .contact_stages import (ccd_stage, correct_stage, detect_stage, moving_bodies,
                             restitution_stage, rows_stage, sleep_stage, solve_stage,
                             solver_masses)
from .event_log import events_add, events_finish, events_reset
from .scratch import ROW_GUESS, take, take_bools, take_rows
from .time_of_impact import rewind_bodies

CCD, COLLIDE, RESTITUTION, SOLVE, CORRECT, EVENTS, SLEEP, N_STAGES = range(8)
STAGE_NAMES = ("ccd", "collide", "restitution", "solve", "correct", "events", "sleep")


@njit(cache=True, inline="always")
def _finite(pos, quat, vel, omega):
    return all_finite(pos, quat, vel, omega)


@njit(cache=True, inline="always")
def _collide(cm, fp, ip, s, masses, start, sleep, warm, toi, h, cap, store):
    """collide: detection, waking, rows; (contacts, R, I, M, MI, rows computed)."""
    pos, quat, vel, omega, awake = s
    a, b, point, normal, depth, key, k, woke = detect_stage(cm, fp, ip, pos, quat, awake, sleep,
                                                            cap, store)
    if woke:
        solver_masses(cm, awake, masses[0], masses[1])
    contacts = (a, b, point, normal, depth, key)
    R, I, M, MI = rows_stage(cm, fp, ip, borrow(contacts), pos, quat, vel, omega, masses[0],
                             masses[1], warm, toi, h, start[2], start[3], store)
    return contacts, R, I, M, MI, k


@njit(cache=True, inline="always")
def _correct(cm, fp, ip, R, I, s, vel0, omega0, target, tau, toi, slide, h, store):
    """correct, then the rest of the substep of the bodies ccd moved back,
    searched like a whole substep (time_of_impact.py)."""
    pos, quat, vel, omega, awake = s
    rewound = take_bools(store, len(toi))
    again = False
    for i in range(len(toi)):
        rewound[i] = toi[i] >= 0.0
        again |= rewound[i]
    p_impact = pos.copy() if again else pos[:0]
    q_impact = quat.copy() if again else quat[:0]
    correct_stage(fp, ip, R, I, pos, quat, vel, omega, vel0, omega0, target, tau, toi, slide, h,
                  store)
    if again:
        rewind_bodies(cm.kind, cm.dims, cm.reach, cm.is_static, rewound, p_impact, q_impact,
                      pos, quat, omega, fp[CCD_THRESHOLD], fp[MARGIN], ip[CCD_ITERATIONS],
                      fp[CCD_TOLERANCE], toi)


@njit(cache=True, inline="always")
def _events(events, contacts, R, friction, moving_mask, last, store):
    a, b, point, normal, depth, key = contacts
    if len(R):
        lam, speed = take(store, len(R)), take(store, len(R))
        for c in range(len(R)):
            lam[c] = R[c, LAM]
            speed[c] = -R[c, U0]
        events_add(events, key, a, b, point, normal, depth, lam, friction, speed)
    if last:
        events_finish(events, moving_mask)


@njit(cache=True, inline="always")
def _any_rewound(toi):
    for i in range(len(toi)):
        if toi[i] >= 0.0:
            return True
    return False


@njit(cache=True, inline="always")
def _velocities(vel, omega, moves, store):
    """Copies of vel and omega in scratch (collision/scratch.py); empty when not `moves`."""
    k = len(vel) if moves else 0
    v, w = take_rows(store, k, 3), take_rows(store, k, 3)
    if moves:
        v[:] = vel
        w[:] = omega
    return v, w


# Inlined in the step loop (step_loop._one_step): a call passed its 40-odd
# arrays field by field on the stack once per substep, about a tenth of a
# resting ball's step.
@njit(cache=True, inline="always")
def run(cm, fp, ip, s, masses, start, sleep, warm, events, h, dt, first, last, cap, store, prof,
        t):
    """The contact stages of one substep; -1 or the failing stage. s = (pos,
    quat, vel, omega, awake); start = the same four at the start of the
    substep; masses = the solver's (inv_mass, inv_inertia),
    updated here when bodies wake or sleep; cap: scratch.py's counts (the
    row-count guess updated here); store: the substep's scratch (scratch.py),
    whose views need no keep_alive; t the cycle counter at the start of the
    stages (each stage's time runs from the end of the one before, its
    finite check included: cycle_clock.lap)."""
    pos, quat, vel, omega, awake = s
    toi = take(store, len(pos))
    toi[:] = -1.0
    if first:
        events_reset(events)
    if ip[CCD_ON]:
        moved = ccd_stage(cm, fp, ip, pos, quat, omega, awake, start[0], start[1], toi, store)
        ok = moved == 0 or _finite(pos, quat, vel, omega)      # no body moved back: nothing new
        t = lap(prof, CCD, t)
        if not ok:
            return CCD
    made = _collide(cm, fp, ip, s, masses, start, sleep, warm, toi, h, cap[ROW_GUESS], store)
    rows = borrow(made)
    cap[ROW_GUESS] = rows[5] + rows[5] // 8 + 4
    # with no contact and no body moved back, the solve changes no velocity
    # and the correct stage has nothing to move: it is skipped
    moves = len(rows[1]) > 0 or _any_rewound(toi)
    before = _velocities(vel, omega, moves, store)
    t = lap(prof, COLLIDE, t)
    failed = _respond(cm, fp, ip, s, masses, start, sleep, warm, events, h, dt, last, prof, rows,
                      toi, before, moves, store, t)
    keep_alive(made)
    return failed


@njit(cache=True, inline="always")
def _respond(cm, fp, ip, s, masses, start, sleep, warm, events, h, dt, last, prof, rows, toi,
             before, moves, store, t):
    """restitution, solve, correct, events and sleep on the collide stage's
    rows = (contacts, R, I, M, MI, k), timed from t; -1 or the failing stage."""
    pos, quat, vel, omega, awake = s
    contacts, R, I, M, MI, _ = rows
    target, tau, J = restitution_stage(fp, ip, R, I, M, MI, vel, omega, start[2], start[3], h,
                                       store)
    ok = velocities_finite(vel, omega)          # the pass changes velocities only
    t = lap(prof, RESTITUTION, t)
    if not ok:
        return RESTITUTION
    friction, _, slide = solve_stage(fp, ip, R, I, M, MI, contacts[5], vel, omega, warm, J,
                                     (masses[0], masses[1], quat), store)
    ok = velocities_finite(vel, omega)          # as does the solve
    t = lap(prof, SOLVE, t)
    if not ok:
        return SOLVE
    if moves:
        _correct(cm, fp, ip, R, I, s, before[0], before[1], target, tau, toi, slide, h, store)
    ok = _finite(pos, quat, vel, omega)
    t = lap(prof, CORRECT, t)
    if not ok:
        return CORRECT
    moving = moving_bodies(cm.is_static, awake, store)
    _events(events, contacts, R, friction, moving, last, store)
    t = lap(prof, EVENTS, t)
    if last and ip[SLEEP_ON]:
        if sleep_stage(cm, fp, R, I, awake, vel, omega, sleep, dt):
            solver_masses(cm, awake, masses[0], masses[1])
        lap(prof, SLEEP, t)
    return -1
