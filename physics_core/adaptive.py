"""Error-controlled integration of the force effects between the fixed steps
(`integrator: adaptive`, accuracy_params.py for the scene keys).

The World still steps on its dt grid (and contacts on its substeps,
h = dt / substeps); `advance(span, ...)` replaces one fixed integrator
substep: it covers [t, t + span] with internal steps of an embedded
Runge–Kutta pair (embedded_rk.py), each accepted when the error norm of
adaptive_kernels.step_error is ≤ 1, and lands exactly on t + span (the last
internal step is cut short, or stretched by at most 1 %, to end there).
So no internal step crosses a substep boundary, where the contact stages
run: a new contact or a bounce always ends the internal step, and the
substep after it restarts from the changed velocities with a freshly
evaluated first slope.

Step-size control: the PI controller of Hairer & Wanner's DOPRI5 (Solving
ODEs I, II.4 eq. 4.13, and IV.2 "stabilized step size control", Gustafsson
1991): after an accepted step with scaled error err, following one of
err_prev, h ← h · min(fac_max, max(fac_min, 0.9 · err^(−α) · err_prev^β)),
α = 1/(q+1) − 0.75 β, β = 0.04 (0.08 for the third-order pair, whose
steps sit nearer their stability bound on stiff springs), fac_min = 0.2,
fac_max = 5 (1 right after a rejection, so a rejected size is not grown
back at once). A rejected step is retried from the same state with
h · max(fac_min, 0.9 · err^(−1/(q+1))).
A step at min_step is accepted whatever its error (counted as
`steps_at_min_step`); a non-finite error is accepted once at min_step and
ends the span, so the step's finite check names the bodies. The proposed
size and err_prev carry over from span to span (stats[H_NEXT], stats[ERR_PREV]);
they are the controller's only state, reset with the World, and part of what makes a replay exact:
the same scene and commands give the same internal steps and bits.

Statistics (stats, float64 (N_STATS,)): cumulative slots and the same for
the current world.step(n) call (the World clears the CALL_ slots first).
"""
import math

import numpy as np
from numba import njit

from .accuracy_params import LOCAL_SHARE
from .adaptive_kernels import (ATOL_Q, ATOL_V, ATOL_W, ATOL_X, RTOL, carry_last_slope, commit,
                               load_start, stage_pose, stage_slope, step_error)
from .embedded_rk import METHODS
from .integration import forces_at, spins
from .integrator_kernels import WIDTH

ADAPTIVE = 4                                               # the step loop's integrator code
MIN_STEP, MAX_STEP, EXPONENT, BETA, N_PARAMS = 5, 6, 7, 8, 9   # params slots after the tolerances
SAFETY, FAC_MIN, FAC_MAX = 0.9, 0.2, 5.0
STRETCH = 1.01                                           # last step may grow this much to land
H_NEXT = 0
STEPS, REJECTED, EVALS, AT_MIN, MIN_H, MAX_H, MAX_ERR = range(1, 8)
CALL = 7                                                 # offset of the per-call slots
ERR_PREV = 1 + 2 * CALL
N_STATS = ERR_PREV + 1
ERR_PREV_START = 1e-4                                    # DOPRI5's facold before the first step
STAT_NAMES = ("internal_steps", "rejected_steps", "force_evaluations", "steps_at_min_step",
              "smallest_step_s", "largest_step_s", "max_local_error")


def adaptive_data(accuracy, n, stats=None):
    """(params, tableau, stats, scratch) for `advance` from AccuracyParams; a
    given `stats` array is kept (its counters), with the controller restarted."""
    tab = METHODS[accuracy.method]
    assert np.array_equal(tab.A[-1, :-1], tab.b[:-1]), "advance needs an FSAL pair"
    params = np.zeros(N_PARAMS)
    # the scene's tolerances are for the run's error; each step's local error gets LOCAL_SHARE of it
    params[[RTOL, ATOL_X, ATOL_V, ATOL_Q, ATOL_W]] = LOCAL_SHARE * np.array(
        [accuracy.relative, accuracy.position, accuracy.velocity, accuracy.orientation,
         accuracy.angular_velocity])
    params[MIN_STEP], params[MAX_STEP], params[EXPONENT], params[BETA] = (
        accuracy.min_step, accuracy.max_step, tab.error_exponent, tab.pi_beta)
    stats = new_stats() if stats is None else stats
    restart(stats)
    scratch = (np.zeros((tab.stages, n, WIDTH)), np.zeros((n, WIDTH)), np.zeros((n, WIDTH)))
    return params, (tab.A.copy(), tab.b.copy(), tab.e.copy()), stats, scratch


def unused_adaptive():
    """The same types with no rows, for the fixed-step integrators (one compiled step type)."""
    z = np.zeros((0, WIDTH))
    return (np.zeros(N_PARAMS), (np.zeros((1, 1)), np.zeros(1), np.zeros(1)), new_stats(),
            (np.zeros((1, 0, WIDTH)), z, z.copy()))


def new_stats():
    stats = np.zeros(N_STATS)
    clear_call(stats)
    stats[MIN_H] = math.inf
    restart(stats)
    return stats


def restart(stats):
    """The controller's state back to its start (a new or reset World)."""
    stats[H_NEXT], stats[ERR_PREV] = 0.0, ERR_PREV_START


def clear_call(stats):
    """Zero the per-call slots (the World does this before each world.step(n))."""
    stats[CALL + STEPS:CALL + MAX_ERR + 1] = 0.0
    stats[CALL + MIN_H] = math.inf


def read_stats(stats, call=False):
    """{name: value} of the cumulative (or the last call's) slots."""
    base = CALL if call else 0
    out = {name: float(stats[base + slot]) for name, slot in zip(STAT_NAMES, range(STEPS, MAX_ERR + 1))}
    for name in STAT_NAMES[:4]:
        out[name] = int(out[name])
    if out["internal_steps"] == 0:
        out["smallest_step_s"] = out["largest_step_s"] = 0.0
    return out


@njit(cache=True)
def _factor(err, exponent, beta, err_prev, fac_max):
    """The step-size ratio after a step of scaled error err (module docstring;
    beta = 0 for the plain controller after a rejection)."""
    if err != err:
        return FAC_MIN
    if err == 0.0:
        return fac_max
    return min(fac_max, max(FAC_MIN, SAFETY * err ** (0.75 * beta - exponent) * err_prev ** beta))


@njit(cache=True)
def _count(stats, slot, value):
    stats[slot] += value
    stats[CALL + slot] += value


@njit(cache=True)
def _record_accepted(stats, h, err, at_min):
    _count(stats, STEPS, 1.0)
    if at_min:
        _count(stats, AT_MIN, 1.0)
    for base in (0, CALL):
        stats[base + MIN_H] = min(stats[base + MIN_H], h)
        stats[base + MAX_H] = max(stats[base + MAX_H], h)
        if err == err:
            stats[base + MAX_ERR] = max(stats[base + MAX_ERR], err)


@njit(cache=True)
def _attempt(h, fresh, rotating, data, state, body, loads, tab, params, scratch, work, prof):
    """One trial step of length h from the state: (scaled error, force
    evaluations); y_new left in scratch[2]. Stage 0 is the state itself, and
    its slope is already in K[0] unless `fresh`."""
    pos, quat, vel, omega = state
    inv_mass, inertia, inv_inertia, iso = body
    A, b, e = tab
    K, y0, ynew = scratch
    F, T, vec, stage_quat = work[0], work[1], work[2], work[3]
    x, v = vec[0], vec[1]
    q, w = (stage_quat, vec[2]) if rotating else (quat, omega)
    evals = 0
    for j in range(len(b)):                 # one call site: the forces are inlined once
        if j == 0 and not fresh:
            continue
        if j == 0:
            sx, sq, sv, sw = pos, quat, vel, omega
        else:
            stage_pose(rotating, y0, K, A[j], h, x, q, v, w, inv_inertia, iso)
            sx, sq, sv, sw = x, q, v, w
        forces_at(data, loads, sx, sq, sv, sw, F, T, prof)
        stage_slope(rotating, K, j, sq, sv, sw, F, T, inv_mass)
        evals += 1
    return step_error(rotating, y0, K, b, e, h, ynew, inv_inertia, params), evals


@njit(cache=True)
def _proposal(h_try, h, last, err, params, stats, may_grow):
    """The next step size after an accepted one (the PI rule, and err_prev
    updated); a step cut short to land on the span's end keeps the size
    proposed before it."""
    nxt = h_try * _factor(err, params[EXPONENT], params[BETA], stats[ERR_PREV],
                          FAC_MAX if may_grow else 1.0)
    stats[ERR_PREV] = max(err, ERR_PREV_START)
    if last and h_try < h:
        nxt = max(nxt, h)
    return min(max(nxt, params[MIN_STEP]), params[MAX_STEP])


@njit(cache=True)
def _taken(err, h_try, params):
    """Whether a trial step is taken: within tolerance, forced at min_step, or
    non-finite (taken once, so that the finite check names the bodies)."""
    return err <= 1.0 or h_try <= params[MIN_STEP] or err != err


@njit(cache=True)
def _first_size(stats, params):
    """The carried-over proposal, or max_step on a fresh controller."""
    h = stats[H_NEXT] if stats[H_NEXT] > 0.0 else params[MAX_STEP]
    return min(h, params[MAX_STEP])


@njit(cache=True)
def advance(span, data, state, body, loads, model_torque, adaptive, work, prof):
    """Integrate the force effects over [t, t + span] (s) with error control;
    state = (pos, quat, vel, omega) updated in place; body = (inv_mass,
    inertia, inv_inertia, iso); loads as integration.forces_at's; work =
    integration_work(n); prof as in integration.forces."""
    params, tab, stats, scratch = adaptive
    pos, quat, vel, omega = state
    inertia, iso = body[1], body[3]
    rotating = model_torque or loads[4] or spins(omega)
    h = _first_size(stats, params)
    t, fresh, may_grow = 0.0, True, True
    load_start(rotating, pos, quat, vel, omega, inertia, iso, scratch[1])
    while t < span:
        last = h * STRETCH >= span - t
        h_try = span - t if last else h
        err, evals = _attempt(h_try, fresh, rotating, data, state, body, loads, tab, params,
                              scratch, work, prof)
        _count(stats, EVALS, evals)
        fresh = False
        if _taken(err, h_try, params):
            commit(rotating, scratch[2], pos, quat, vel, omega, body[2], iso)
            _record_accepted(stats, h_try, err, not err <= 1.0)
            if err != err:
                return
            t = span if last else t + h_try
            h = _proposal(h_try, h, last, err, params, stats, may_grow)
            carry_last_slope(scratch[0])
            load_start(rotating, pos, quat, vel, omega, inertia, iso, scratch[1])
            may_grow = True
        else:
            _count(stats, REJECTED, 1.0)
            h = max(h_try * _factor(err, params[EXPONENT], 0.0, 1.0, 1.0), params[MIN_STEP])
            may_grow = False
    stats[H_NEXT] = h
