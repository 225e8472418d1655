"""world.step(n) as one compiled loop over steps, substeps and stages.

Each stage is its own compiled function (integration.py for the integrator
and the force effects, collision/contact_substep.py for the contact stages),
timed with the cycle counter into `prof` (one reading at each boundary
between stages: cycle_clock.lap) and followed by the finite check.
Looping in compiled code means a step pays no interpreter cost, and the
inputs (step_inputs.py: one object holding every array) are passed once per
call of world.step(n), not once per step.

`run_steps` returns (steps done, failed stage): failed is -1, or the stage
after which some body's state was not finite (the World names it and the
bodies; the state is left as that stage made it).
"""
import numpy as np
from numba import njit

from .borrowed import borrow
from .collision.contact_substep import N_STAGES
from .collision.contact_substep import run as contact_substep
from .collision.scratch import new_counts, new_scratch, open_arena, take_rows
from .cycle_clock import cycles, lap
from .finite import all_finite
from .adaptive import ADAPTIVE, advance
from .integration import integrate_substep

# prof slots: the contact stages first (contact_substep's own indices), then these
INTEGRATE = N_STAGES
FINITE = N_STAGES + 1
FORCES = N_STAGES + 2          # one per force effect, integration.py's order
FAILED_INTEGRATE = 100


@njit(cache=True, inline="always")
def _integrate(code, h, idata, body, loads, masses, work, adaptive, prof):
    pos, quat, vel, omega, awake = body
    user_force, user_force_offset, user_torque, flags = loads
    inv_mass, inertia, inv_inertia = masses
    if code == ADAPTIVE:          # error-controlled internal steps over this substep (adaptive.py)
        advance(h, idata, (pos, quat, vel, omega), (inv_mass, inertia, inv_inertia, idata[1]),
                (user_force, user_force_offset, user_torque, flags[0] != 0, flags[1] != 0),
                flags[2] != 0, adaptive, work, prof[FORCES:])
    else:
        integrate_substep(code, h, idata, pos, quat, vel, omega, inv_mass, inertia, inv_inertia,
                          user_force, user_force_offset, user_torque, flags[0] != 0, flags[1] != 0,
                          flags[2] != 0, work, prof[FORCES:])


@njit(cache=True, inline="always")
def _copy(store, a):
    """A copy of `a` in the substep's scratch (collision/scratch.py)."""
    out = take_rows(store, a.shape[0], a.shape[1])
    out[:] = a
    return out


@njit(cache=True, inline="always")
def _start(body, store):
    """(pos, quat, vel, omega) at the start of a substep, in kept scratch."""
    return _copy(store, body[0]), _copy(store, body[1]), _copy(store, body[2]), _copy(store, body[3])


# Inlined in the loop over steps (_run), with the contact stages inlined in
# it: one compiled function per world.step(n) call, so the packed inputs are
# unpacked once per call, not passed down once per step and substep.
@njit(cache=True, inline="always")
def _one_step(substeps, dt, code, idata, body, loads, masses, work, contacts, adaptive, prof):
    """One step; -1 or the failed stage."""
    cm, fp, ip, sleep, warm, events, cap, scratch = contacts
    h = dt / substeps
    for sub in range(substeps):
        store = open_arena(scratch, cap)
        start = _start(body, store)
        t = cycles()
        _integrate(code, h, idata, body, loads, masses, work, adaptive, prof)
        t = lap(prof, INTEGRATE, t)
        ok = all_finite(body[0], body[1], body[2], body[3])
        t = lap(prof, FINITE, t)
        if not ok:
            return FAILED_INTEGRATE
        if len(cm.kind):
            failed = contact_substep(cm, fp, ip, body, (masses[0], masses[2]), start, sleep,
                                     warm, events, h, dt, sub == 0, sub == substeps - 1, cap,
                                     store, prof, t)
            if failed >= 0:
                return failed
    return -1


@njit(cache=True)
def run_steps(inputs, n, substeps, dt, code):
    """Up to n steps of `substeps` substeps of dt / substeps with integrator
    `code`; (steps done, failed stage or -1). `inputs` is a
    step_inputs.StepInputs: the integrator's data, the body arrays, the
    loads, the masses, `contacts` = (contact model, float and int
    parameters, sleep state, scratch counts), the warm cache's and the event
    log's typed lists, the contact stages' scratch store
    (collision/scratch.py), adaptive.adaptive_data's tuple (unused_adaptive()
    for a fixed integrator) and the prof slots (their totals, then a copy of
    the totals as they were when this call began)."""
    return _run(n, substeps, dt, code, inputs.idata, inputs.body,
                inputs.loads, inputs.masses, inputs.work, inputs.contacts, inputs.warm_keys,
                inputs.warm_values, inputs.event_ints, inputs.event_floats, inputs.event_counts,
                inputs.scratch, inputs.adaptive, inputs.prof)


@njit(cache=True, inline="always")
def _run(n, substeps, dt, code, idata, body, loads, masses, work, contacts, warm_keys,
         warm_values, event_ints, event_floats, event_counts, scratch, adaptive, prof):
    """run_steps on its inputs unpacked, each borrowed for the call (borrowed.py)."""
    cm, fp, ip, sleep, cap = borrow(contacts)
    lists = borrow((warm_keys, warm_values, event_ints, event_floats, event_counts, scratch))
    packed = (cm, fp, ip, sleep, (lists[0], lists[1]), (lists[2], lists[3], lists[4]), cap,
              lists[5])
    idata, body, loads, masses, work, adaptive, prof = borrow((idata, body, loads, masses, work,
                                                               adaptive, prof))
    half = len(prof) // 2           # the slots' totals before this call, for last_step_profile
    for i in range(half):
        prof[half + i] = prof[i]
    for k in range(n):
        failed = _one_step(substeps, dt, code, idata, body, loads, masses, work, packed, adaptive,
                           prof)
        if failed >= 0:
            return k, failed
    return n, -1


def _read_only(a):
    a.flags.writeable = False
    return a


def no_contacts():
    """(contacts, warm cache, event state, scratch) of a scene without the contacts effect.
    The arrays a real ContactModel takes from the model (material onwards) are
    read-only there, so they are here too: the step then has the same Numba
    types with or without contacts and loads the kernels `make install`
    compiled, instead of compiling a second set at a scene's first step
    (tens of seconds on a loaded machine)."""
    from .collision.contact_data import N_FP, N_IP, ContactModel, new_sleep_state, new_warm_cache
    from .collision.event_log import new_event_state
    z = np.zeros(0)
    cm = ContactModel(np.zeros(0, np.int64), np.zeros((0, 8)), np.zeros(0, np.bool_), z,
                      _read_only(np.zeros(0, np.int64)), _read_only(np.zeros(0)), _read_only(np.zeros(0)),
                      _read_only(np.zeros((0, 3))), _read_only(np.zeros((1, 1))), _read_only(np.zeros((1, 1))))
    return ((cm, np.zeros(N_FP), np.zeros(N_IP, np.int64), new_sleep_state(0), new_counts(0)),
            new_warm_cache(), new_event_state(), new_scratch())
