"""Sequential impulses over the contact rows, compiled (COURSE.md 5; Box2D's solver).

Each contact keeps its accumulated impulses λ (normal, two tangents). An
update computes the change that brings the row's relative velocity to its
target, adds it to λ, clamps λ (normal ≥ 0, tangential inside the friction
cap) and applies only the clamped change. Contacts are visited one after the
other in key order (Gauss–Seidel), so every update sees the velocities the
previous ones left: the order is fixed, hence the result deterministic. The
accumulated, clamped λ makes many simultaneous contacts converge and lets
last substep's λ be applied first (warm starting).

A manifold of two or more points has one friction anchor at its centre
(manifold_friction.py), solved after its points' normal rows. A single
point's friction is one 2-D impulse in the tangent plane, solved with the tangent
block W_tt (friction.py): the impulse that stops the slip, corrected for the
velocity the normal change of the same update gives (W_tn), capped at
μ λ_n. Over the cap, a sliding contact (kinetic, μ_k) takes μ_k λ_n against
the slip it ends the update with (the course's μ_k j along −t;
kinetic_bound); a sticking one keeps the direction of the impulse that
would stop it (the static bound μ_s λ_n).
"""
import math

import numpy as np
from numba import njit

from .contact_build import row_velocity, tangent_world
from .kinetic_bound import kinetic_bound
from .manifold_friction import COUNT, FIRST, M_SLIDING, update_anchor
from .pair_velocity import load_pair, pair_impulse, pair_impulses, pair_velocity, store_pair
from .contact_layout import (BIAS, BODY_A, BODY_B, DIR, G_TN, INV_MASS_A, INV_MASS_B, LAM, MASS_N,
                             MU, SLIDING, STRIDE, TURN_A, TURN_B, W_TT_INV)

_TINY = 1e-300


@njit(cache=True)
def apply_impulse(R, c, r, lam, a, b, vel, omega):
    """Velocity change of both bodies for an impulse lam along row r."""
    ima, imb = R[c, INV_MASS_A] * lam, R[c, INV_MASS_B] * lam
    for i in range(3):
        d = R[c, DIR + STRIDE * r + i]
        vel[a, i] -= ima * d
        omega[a, i] -= lam * R[c, TURN_A + STRIDE * r + i]
        vel[b, i] += imb * d
        omega[b, i] += lam * R[c, TURN_B + STRIDE * r + i]


@njit(cache=True, inline="always")
def warm_start(R, I, vel, omega):
    """Apply the impulses λ the rows start with (loaded from last substep)."""
    for c in range(len(R)):
        a, b = I[c, BODY_A], I[c, BODY_B]
        l0, l1, l2 = R[c, LAM], R[c, LAM + 1], R[c, LAM + 2]
        if l0 != 0.0 or l1 != 0.0 or l2 != 0.0:
            p = pair_impulses(R, c, l0, l1, l2, load_pair(vel, omega, a, b))
            store_pair(vel, omega, a, b, p)


@njit(cache=True)
def friction_cap(R, c, lt1, lt2, ln, sliding):
    """Coulomb's bound |λ_t| ≤ μ λ_n, for one contact: a sliding contact
    takes μ_k λ_n against its slip (kinetic_bound); a sticking one keeps the
    direction of the impulse that would stop it (the static bound μ_s λ_n)."""
    lim = R[c, MU] * ln
    mag2 = lt1 * lt1 + lt2 * lt2
    if not mag2 > lim * lim:
        return lt1, lt2
    if sliding:
        return kinetic_bound(R[c, W_TT_INV], 0.5 * (R[c, W_TT_INV + 1] + R[c, W_TT_INV + 2]),
                             R[c, W_TT_INV + 3], lt1, lt2, lim)
    scale = lim / math.sqrt(mag2 + _TINY)
    return lt1 * scale, lt2 * scale


@njit(cache=True, inline="always")
def update_contact(R, I, c, p):
    """One Gauss–Seidel update of contact c on its pair's velocities p
    (pair_velocity.py); returns (p after it, its largest impulse change)."""
    un = pair_velocity(R, c, 0, p)
    u1 = pair_velocity(R, c, 1, p)
    u2 = pair_velocity(R, c, 2, p)
    old_n, old_1, old_2 = R[c, LAM], R[c, LAM + 1], R[c, LAM + 2]
    ln = max(old_n - R[c, MASS_N] * (un - R[c, BIAS]), 0.0)
    dn = ln - old_n
    # W_tt⁻¹ u_t: the tangential impulse that stops the slip; friction sees
    # the velocity after this normal change (W_tn couples them)
    s1 = R[c, W_TT_INV] * u1 + R[c, W_TT_INV + 1] * u2
    s2 = R[c, W_TT_INV + 2] * u1 + R[c, W_TT_INV + 3] * u2
    lt1 = old_1 - s1 - R[c, G_TN] * dn
    lt2 = old_2 - s2 - R[c, G_TN + 1] * dn
    lt1, lt2 = friction_cap(R, c, lt1, lt2, ln, I[c, SLIDING] != 0)
    R[c, LAM], R[c, LAM + 1], R[c, LAM + 2] = ln, lt1, lt2
    p = pair_impulses(R, c, dn, lt1 - old_1, lt2 - old_2, p)
    return p, max(abs(dn), max(abs(lt1 - old_1), abs(lt2 - old_2)))


@njit(cache=True, inline="always")
def update_normal(R, c, p):
    """The normal row of contact c alone (its friction is its manifold's
    anchor), on the pair's velocities p: (p after it, |Δλ|)."""
    un = pair_velocity(R, c, 0, p)
    old = R[c, LAM]
    ln = max(old - R[c, MASS_N] * (un - R[c, BIAS]), 0.0)
    R[c, LAM] = ln
    return pair_impulse(R, c, 0, ln - old, p), abs(ln - old)


@njit(cache=True, inline="always")
def face_shares(R, MI, shares):
    """shares[c] = Σ_j W_cj over the points j of row c's manifold, for every
    manifold of two or more points (even_share): the velocity change at c
    for a unit impulse on every point. They depend on the rows alone, so
    they are computed once for all the sweeps of a solve. Returns shares."""
    for k in range(len(MI)):
        first, count = MI[k, FIRST], MI[k, COUNT]
        if count < 2:
            continue
        q = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        for c in range(first, first + count):
            q = pair_impulse(R, c, 0, 1.0, q)
        for c in range(first, first + count):
            shares[c] = pair_velocity(R, c, 0, q)
    return shares


@njit(cache=True, inline="always")
def even_share(R, first, count, p, shares):
    """The manifold's normal rows moved together, all from the velocities p:
    each λ_i by (b_i − u_i) / Σ_j W_ij (b_i its target, the bias; Σ_j W_ij
    its velocity change for a unit impulse on every point), kept ≥ 0. It
    is the collision pass's even share (collision_pass._even_start), exact
    where every point needs the same share, as on a face meeting flat; the
    points' own updates (update_normal) follow it. Taken one after another
    alone, in key order, the first corner of a face stopped the approach
    and turned the body before the others were measured, and eight sweeps
    did not even that out: a cube landing at 3 m/s across two cubes, a
    scene symmetric about a plane, left the solve moving out of that
    plane at 0.027 m/s and turning at 0.075 rad/s (with 100 sweeps, in
    the plane), and the 10,000-box pyramid's rows leaned out of the wall
    (131 boxes moved more than 1 cm sideways in its first second; none
    now, and 2 at 3 s).
    The shares Σ_j W_ij are read from `shares` (face_shares): computed at
    every update, the box scenes' step took 18-20 % longer, read, about
    4 %. Returns (p after it, its largest |Δλ|: part of the manifold's
    change, which stops the sweeps)."""
    out, change = p, 0.0
    for c in range(first, first + count):
        if shares[c] > 0.0:
            old = R[c, LAM]
            lam = max(old + (R[c, BIAS] - pair_velocity(R, c, 0, p)) / shares[c], 0.0)
            R[c, LAM] = lam
            out = pair_impulse(R, c, 0, lam - old, out)
            if not abs(lam - old) < change:
                change = abs(lam - old)
    return out, change


@njit(cache=True, inline="always")
def update_points(R, M, MI, k, first, count, p, shares):
    """One update of manifold k of two or more points (rows first..first +
    count − 1) on its pair's velocities p: their normal rows (first moved
    together, even_share: `shares` their Σ_j W_ij, face_shares),
    then their friction anchor (manifold_friction.py). Returns (p after
    it, its largest impulse change; NaN if any is NaN)."""
    p, change = even_share(R, first, count, p, shares)
    for c in range(first, first + count):
        p, d = update_normal(R, c, p)
        if not d < change:
            change = d
    p, d = update_anchor(R, M, k, first, count, MI[k, M_SLIDING] != 0, p)
    return p, (d if not d < change else change)


@njit(cache=True)
def sweep_manifolds(R, I, M, MI, vel, omega, changes, shares):
    """One Gauss–Seidel sweep, manifold by manifold in key order, each on
    its two bodies' velocities loaded once and stored once
    (pair_velocity.py), each manifold's largest change written to
    changes[k]; shares: a face's points' Σ_j W_ij (face_shares). Returns
    the largest change.
    A single point is updated by update_contact, two or more by
    update_points, dispatched here: every further inlined layer the tuple
    of velocities is returned through made the sweep slower (a pile of
    1,000 spheres, 1,424 contacts: 230 µs a sweep through two layers, 176
    through one, 130 with none)."""
    change = 0.0
    for k in range(len(MI)):
        first, count = MI[k, FIRST], MI[k, COUNT]
        a, b = I[first, BODY_A], I[first, BODY_B]
        p = load_pair(vel, omega, a, b)
        if count < 2:
            p, d = update_contact(R, I, first, p)
        else:
            p, d = update_points(R, M, MI, k, first, count, p, shares)
        store_pair(vel, omega, a, b, p)
        changes[k] = d
        if not d < change:
            change = d
    return change


@njit(cache=True, inline="always")
def solve_velocities(R, I, M, MI, vel, omega, iterations, stops, changes, shares=None):
    """At most `iterations` sweeps over every manifold; stops after a sweep
    that changed no impulse by more than `limit` (N·s; < 0: never), stops =
    (limit, settle, stall), unless the sweeps converge fast enough to reach
    `settle` (≤ limit) in the sweeps left (_settling): they then go on to
    it, and a group of bodies settled that far is left out of the shock
    sweep (shock_propagation.leave_out_settled), whose tables cost several
    sweeps. They also stop, with `limit` > 0, after a sweep whose largest
    change is above `stall` times the largest two sweeps before (math.inf:
    never): the sweeps then only move impulses along a direction that
    changes almost no velocity, by about as much every sweep. A box's four
    corners share its load in a line of ways (resting_block.py), and on a
    pile of cubes at rest the sweeps move the load along that line,
    converging at about 0.992 a sweep (its largest change 5.4e-5 N·s at the
    third sweep, 5.2e-5 at the eighth); every other manifold has converged
    below that level.
    solve_stage passes shock_propagation.STALL where the shock sweep
    follows, which settles what they leave. A NaN change never stops early.
    Returns (sweeps done, the last sweep's largest impulse change; NaN if
    one was); changes[k] is manifold k's largest change in that last
    sweep. shares: scratch of len(R) for face_shares (None: a new array; the
    step passes a view of its substep's scratch)."""
    limit, settle, stall = stops
    if shares is None:
        shares = np.empty(len(R))
    face_shares(R, MI, shares)
    change = previous = math.inf
    changes[:] = math.inf
    for sweep in range(iterations):
        earlier, previous = previous, change
        change = sweep_manifolds(R, I, M, MI, vel, omega, changes, shares)
        if limit > 0.0 and change < limit:
            if not _settling(change, previous, settle, iterations - sweep - 1):
                return sweep + 1, change
        elif limit > 0.0 and change > stall * earlier:
            return sweep + 1, change
    return iterations, change


@njit(cache=True, inline="always")
def _settling(change, before, settle, left):
    """Whether sweeps that keep shrinking the change at this sweep's rate
    (change / before) get it under `settle` within `left` more sweeps,
    and have not yet. After the first sweep (before = inf, rate 0) one more
    sweep is taken, if any is left, to measure the rate."""
    if not change >= settle:
        return False
    rate = change / before
    return rate < 1.0 and change * rate ** left < settle


@njit(cache=True, inline="always")
def _friction_row(R, c, friction):
    """Contact c's tangential impulse as a world vector λ_t1 t1 + λ_t2 t2."""
    for i in range(3):
        friction[c, i] = tangent_world(R, c, R[c, LAM + 1], R[c, LAM + 2], i)


@njit(cache=True, inline="always")
def _friction_and_slip_row(R, I, c, vel, omega, friction, slip):
    a, b = I[c, BODY_A], I[c, BODY_B]
    _friction_row(R, c, friction)
    u1 = row_velocity(R, c, 1, a, b, vel, omega)
    u2 = row_velocity(R, c, 2, a, b, vel, omega)
    slip[c] = math.sqrt(u1 * u1 + u2 * u2)


@njit(cache=True, inline="always")
def friction_and_slip(R, I, vel, omega, friction, slip):
    """Per contact: the tangential impulse as a world vector λ_t1 t1 + λ_t2 t2
    (it survives a change of tangent basis) and the slip speed |u_t| now."""
    for c in range(len(R)):
        _friction_and_slip_row(R, I, c, vel, omega, friction, slip)


@njit(cache=True, inline="always")
def friction_of(R, I, friction, moved):
    """The tangential impulses (world vectors) of the contacts with a body
    marked `moved` (n,), read again after the shock sweep: the others'
    impulses are those they were computed from. Their slip is not: only the
    warm cache reads it, and it keeps the sweeps' own."""
    for c in range(len(R)):
        if moved[I[c, BODY_A]] or moved[I[c, BODY_B]]:
            _friction_row(R, c, friction)


@njit(cache=True, inline="always")
def least_mass(R):
    m = math.inf
    for c in range(len(R)):
        m = min(m, R[c, MASS_N])
    return m

