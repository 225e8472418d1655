"""Shock propagation: a last, ordered sweep of the contact solve in which each
body rests on what holds it (Guendelman, Bridson & Fedkiw 2003, "Nonconvex
rigid bodies with stacking", section 7; Erleben 2004, ch. 7).

Sequential impulses pass a load down a stack one contact per sweep, and a
light body between a heavy one and the ground converges at about
(1 − m_light/m_heavy) per sweep: in 8 sweeps a 20-box stack or a 1,000 kg
cube on a 1 kg one is far from converged, the residual approach
velocities sink the bodies into each other and position correction cannot
keep up (the heavy cube went through the light one).

After the sweeps, bodies get support layers: 0 for the immovable ones
(static or asleep, zero inverse mass), and 1 + the least layer of the
bodies they touch otherwise (breadth-first over the contacts). The
manifolds between two layers are then solved once more, layer after
layer from the lowest up, with the layer below immovable (its side of a
row takes no impulse and the effective masses are the upper body's
alone): every contact then ends with the upper body not approaching the
lower and, within the friction cone, not slipping on it, whatever the
mass ratio. With the layer below immovable, two bodies of a layer share
no movable body, so each is settled on its own: its manifolds swept
until its contact-point velocities settle, in copies with the lower side
frozen that stay in cache while it converges, then the next body.
Contacts within one layer carry no support from below (neither body
rests on the other) and were solved by the sweeps; leaving them out
lets each body settle on its own supports instead of every body of a
layer converging as one group. Bodies that touch nothing immovable
(free-flying groups) are not visited, so their momentum is kept exactly.
This removes the reaction of an upper body on the lower within this sweep only: the
warm-started sweeps before it carry the loads down.

A body stops sweeping once its change stalls (STALL), and a layer whose
settle raised its bodies' kinetic energy is undone (GAIN,
_settle_layer): a body on two supports that move apart cannot follow
both, and making it try threw the top boxes off a tall pyramid.

On a converged solve the sweep changes nothing (no contact approaches or
slips); it only removes what the sweeps left, so a group of bodies whose
manifolds all ended the sweeps changing no impulse by more than a
hundredth of their stop is left out (leave_out_settled), and the sweep
returns at once when every group is (shock_sweep). The warm cache keeps the
sweeps' own impulses (contact_stages.solve_stage), so the next substep's
solve starts from its own converging values.
"""
import math

import numpy as np
from numba import njit

from ..quaternion import rotate_inverse_one, row4
from .contact_build import effective_masses, normal_mass
from .contact_layout import (ARM_A, ARM_B, BODY_A, BODY_B, INV_MASS_A, INV_MASS_B, LAM, MASS_N,
                             STRIDE, TURN_A, TURN_B)
from .manifold_friction import COUNT, FIRST, IMA, IMB, M_LAM, TA, TB, _invert
from .resting_block import MANIFOLDS, WS_SHAPE, settle_resting
from .scratch import cursor, rewind, take, take_bools, take_int_rows, take_ints, take_rows
from .pair_velocity import load_pair, store_pair
from .sequential_impulses import face_shares, update_contact, update_points

UNREACHED = np.int64(1) << 40
# A body's sweeps have stalled when a sweep's change is above this fraction
# of the change two sweeps before: a body on several supports can trade
# impulses between them in a cycle that more sweeps do not end (a pyramid's
# box on two boxes kept changing by 7.35e-4 m/s a sweep from its third sweep
# to its sixteenth; a pile's second layer by 6.9e-3 m/s). A single support,
# as in a stack or the 1000:1 pair, converges well inside the factor. The
# sequential-impulse sweeps before this one stop by the same rule
# (sequential_impulses.solve_velocities).
STALL = 0.9
# A layer's settle may not raise its bodies' kinetic energy by more than this
# fraction (_settle_layer). Measured: converging a box sliding on the floor
# raises it by up to 1e-6 (its normal impulses re-balanced); the layers of a
# 300-box pyramid that were thrown off gained 2.5 % (median), 9 % (90th
# percentile), 69 % at most, per substep
GAIN = 1e-4


@njit(cache=True)
def _neighbours(I, MI, n, store):
    """CSR adjacency of the contact graph, an entry a manifold (its rows share
    one body pair): (start (n + 1), other body per entry), in the substep's
    scratch (scratch.py)."""
    start = take_ints(store, n + 1)
    start[:] = 0
    for k in range(len(MI)):
        start[I[MI[k, FIRST], BODY_A] + 1] += 1
        start[I[MI[k, FIRST], BODY_B] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    fill = take_ints(store, n)
    fill[:] = start[:-1]
    other = take_ints(store, 2 * len(MI))
    for k in range(len(MI)):
        a, b = I[MI[k, FIRST], BODY_A], I[MI[k, FIRST], BODY_B]
        other[fill[a]] = b
        fill[a] += 1
        other[fill[b]] = a
        fill[b] += 1
    return start, other


@njit(cache=True)
def support_layers(R, I, MI, n, store):
    """((n,) breadth-first layer of every body from the immovable ones (a row
    side with zero inverse mass) over the manifolds, UNREACHED elsewhere;
    the contact graph (_neighbours)). A layer is a distance in that graph,
    so it does not depend on the order the search meets the bodies in; a
    manifold's rows share their bodies and inverse masses, so its first
    row stands for them all."""
    layer = take_ints(store, n)
    layer[:] = UNREACHED
    queue = take_ints(store, n)
    tail = 0
    for k in range(len(MI)):
        c = MI[k, FIRST]
        for side, body in ((INV_MASS_A, I[c, BODY_A]), (INV_MASS_B, I[c, BODY_B])):
            if R[c, side] == 0.0 and layer[body] != 0:
                layer[body] = 0
                queue[tail] = body
                tail += 1
    start, other = _neighbours(I, MI, n, store)
    head = 0
    while head < tail:
        i = queue[head]
        head += 1
        for e in range(start[i], start[i + 1]):
            j = other[e]
            if layer[j] == UNREACHED:
                layer[j] = layer[i] + 1
                queue[tail] = j
                tail += 1
    return layer, (start, other)


@njit(cache=True, inline="always")
def holds_something(R):
    """Whether some contact has an immovable side (zero inverse mass): without
    one the sweep has no layer to start from and visits nothing."""
    for c in range(len(R)):
        if R[c, INV_MASS_A] == 0.0 or R[c, INV_MASS_B] == 0.0:
            return True
    return False


@njit(cache=True, inline="always")
def _unsettled_count(MI, unsettled):
    """How many manifolds' last sweep changed an impulse by `bound` or more (or NaN)."""
    changes, bound = unsettled
    count = 0
    for k in range(len(MI)):
        count += not changes[k] < bound
    return count


@njit(cache=True, inline="always")
def _in_sweep(body_layer):
    """A movable body the search reached (layer 1 to below UNREACHED): the
    only kind the sweep gives a velocity change."""
    return 0 < body_layer < UNREACHED


@njit(cache=True, inline="always")
def swept_bodies(layer, store):
    """(n,) the bodies whose velocities the sweep may have changed (shock_sweep's
    layers, _in_sweep), in scratch."""
    out = take_bools(store, len(layer))
    for i in range(len(layer)):
        out[i] = _in_sweep(layer[i])
    return out


@njit(cache=True, inline="always")
def _reach(i, layer, active, queue, tail):
    """Body i queued (returns the new tail) if it is in the sweep and not yet active."""
    if not _in_sweep(layer[i]) or active[i]:
        return tail
    active[i] = True
    queue[tail] = i
    return tail + 1


@njit(cache=True)
def leave_out_settled(I, MI, layer, graph, unsettled, store):
    """Every movable body not connected, through movable bodies, to a manifold
    whose last sweep changed an impulse by `bound` or more (unsettled =
    (changes, bound), sequential_impulses.solve_velocities) gets layer
    UNREACHED: the sweep leaves its group out, as it would leave out the
    whole solve (contact_stages.solve_stage). Groups share no body, so the
    others are swept as before. Returns the number of bodies kept."""
    changes, bound = unsettled
    start, other = graph
    active = take_bools(store, len(layer))
    active[:] = False
    queue = take_ints(store, len(layer))
    tail = 0
    for k in range(len(MI)):
        if not changes[k] < bound:
            tail = _reach(I[MI[k, FIRST], BODY_A], layer, active, queue, tail)
            tail = _reach(I[MI[k, FIRST], BODY_B], layer, active, queue, tail)
    head = 0
    while head < tail:
        i = queue[head]
        head += 1
        for e in range(start[i], start[i + 1]):
            tail = _reach(other[e], layer, active, queue, tail)
    for i in range(len(layer)):
        if _in_sweep(layer[i]) and not active[i]:
            layer[i] = UNREACHED
    return tail


@njit(cache=True, inline="always")
def _make_immovable(T, k, inv_mass, turn):
    """Entry k's side (its inverse-mass column, its nine turn columns) set to
    +0.0. A side immovable already (a static or sleeping body, the ground
    under a pile) holds +0.0 there as the row was built, so freezing it
    again changes no number of the entry."""
    T[k, inv_mass] = 0.0
    for r in range(3):
        for i in range(3):
            T[k, turn + STRIDE * r + i] = 0.0


@njit(cache=True, inline="always")
def _freeze_row(R, c, side):
    """Row c with body `side` (0: a, 1: b) immovable: no impulse reaches it
    (its effective masses: _row_masses, when a sweep needs them)."""
    inv_mass, turn = (INV_MASS_A, TURN_A) if side == 0 else (INV_MASS_B, TURN_B)
    _make_immovable(R, c, inv_mass, turn)


@njit(cache=True, inline="always")
def _freeze_anchor(M, k, side):
    inv_mass, turn = (IMA, TA) if side == 0 else (IMB, TB)
    _make_immovable(M, k, inv_mass, turn)


@njit(cache=True, inline="always")
def _row_masses(R, c, anchored):
    """Row c's effective masses from its columns as they are: the row of an
    anchored manifold (its friction is the anchor's) only its normal's, the
    only one of its masses the sweeps read. On a side immovable already
    they are the numbers the row was built with (the same functions of the
    same columns)."""
    if anchored:
        R[c, MASS_N] = normal_mass(R, c)
    else:
        effective_masses(R, c)


@njit(cache=True, inline="always")
def _frozen_masses(one_sided, w):
    """The effective masses of the one-sided copies' rows and anchors, their
    lower side frozen (_one_sided): what a body's sweeps read. The resting
    solve (resting_block.py) reads none of them, so a body it settles
    never computes them. w: (3, 3) scratch."""
    R1, I1, M1, MI1 = one_sided
    for m in range(len(MI1)):
        first, count = MI1[m, FIRST], MI1[m, COUNT]
        for c in range(first, first + count):
            _row_masses(R1, c, count >= 2)
        if count >= 2:
            _invert(M1, m, w)


@njit(cache=True, inline="always")
def _copy_row(T, k, T1, m):
    """T1[m] = T[k] as a plain loop (a row slice assignment took twice as long)."""
    for j in range(T.shape[1]):
        T1[m, j] = T[k, j]


@njit(cache=True, inline="always")
def _row_count(MI, ms):
    """The rows of manifolds ms."""
    rows = 0
    for k in ms:
        rows += MI[k, COUNT]
    return rows


@njit(cache=True, inline="always")
def _one_sided(R, I, M, MI, layer, order, store):
    """Compact copies (R1, I1, M1, MI1) of the manifolds of `order` (one
    body's with the layer below, for its sweeps), in that order, with the
    lower layer's side of every row immovable (the effective masses as they
    were: _frozen_masses).
    A single point has no friction anchor (manifold_friction.py): its M1 row
    is left unwritten, and _scatter_impulses does not read it."""
    rows = _row_count(MI, order)
    R1, I1 = take_rows(store, rows, R.shape[1]), take_int_rows(store, rows, I.shape[1])
    M1, MI1 = take_rows(store, len(order), M.shape[1]), take_int_rows(store, len(order), MI.shape[1])
    r = 0
    for m in range(len(order)):
        k = order[m]
        first, count = MI[k, FIRST], MI[k, COUNT]
        if count >= 2:
            _copy_row(M, k, M1, m)
        _copy_row(MI, k, MI1, m)
        MI1[m, FIRST] = r
        side = 0 if layer[I[first, BODY_A]] < layer[I[first, BODY_B]] else 1
        for c in range(first, first + count):
            _copy_row(R, c, R1, r)
            _copy_row(I, c, I1, r)
            _freeze_row(R1, r, side)
            r += 1
        if count >= 2:
            _freeze_anchor(M1, m, side)
    return R1, I1, M1, MI1


@njit(cache=True)
def _upward_order(I, MI, layer, store):
    """(order, top, upper): the manifolds between two layers (touching
    something immovable), by (higher layer, the body in it, key order) (two
    stable counting sorts: deterministic), the higher layer of each and its
    body there: a layer's manifolds come in runs, one run for each body
    they hold up."""
    top, up = take_ints(store, len(MI)), take_ints(store, len(MI))
    between = take_ints(store, len(MI))
    m = 0
    for k in range(len(MI)):
        a, b = I[MI[k, FIRST], BODY_A], I[MI[k, FIRST], BODY_B]
        la, lb = layer[a], layer[b]
        top[k], up[k] = max(la, lb), (a if la > lb else b)
        if top[k] != UNREACHED and min(la, lb) != top[k]:   # both reached, apart
            between[m] = k
            m += 1
    order = _counting_order(_counting_order(between[:m], up, len(layer), store), top,
                            len(layer), store)
    tops, uppers = take_ints(store, m), take_ints(store, m)
    for s in range(m):
        tops[s], uppers[s] = top[order[s]], up[order[s]]
    return order, tops, uppers


@njit(cache=True)
def _counting_order(items, key, limit, store):
    """`items` stably sorted by key[item] (0 <= key < limit; a layer and a body
    index are less than the body count): a counting sort in scratch,
    O(items + limit)."""
    start = take_ints(store, limit + 1)
    start[:] = 0
    for k in items:
        start[key[k] + 1] += 1
    for i in range(limit):
        start[i + 1] += start[i]
    out = take_ints(store, len(items))
    for k in items:
        out[start[key[k]]] = k
        start[key[k]] += 1
    return out


@njit(cache=True, inline="always")
def _lever(R, first, count):
    """The longest lever arm |r × d| of the manifold's rows (m): a change Δω of
    either body moves a contact point by at most |Δω| times it. One square
    root, of the largest |r × d|² (a correctly rounded root keeps the order)."""
    lever2 = 0.0
    for c in range(first, first + count):
        for o in range(0, 3 * STRIDE, STRIDE):
            for arm in (ARM_A + o, ARM_B + o):
                lever2 = max(lever2, R[c, arm] ** 2 + R[c, arm + 1] ** 2 + R[c, arm + 2] ** 2)
    return math.sqrt(lever2)


@njit(cache=True, inline="always")
def _point_change(p0, p, o, lever):
    """Largest change of one body's contact-point velocity between pair
    velocities p0 and p (pair_velocity.py; o = 0: body a, 6: body b), m/s."""
    dv = dw = 0.0
    for j in range(3):
        dv = max(dv, abs(p[o + j] - p0[o + j]))
        dw = max(dw, abs(p[o + 3 + j] - p0[o + 3 + j]))
    return dv + dw * lever


@njit(cache=True, inline="always")
def _update(R1, I1, M1, MI1, m, vel, omega, lever, shares):
    """One update of manifold m (a face's points first moved together,
    sequential_impulses.update_points, with their shares); returns the
    largest change of a contact-point velocity of its bodies it made (m/s)."""
    first, count = MI1[m, FIRST], MI1[m, COUNT]
    a, b = I1[first, BODY_A], I1[first, BODY_B]
    p0 = load_pair(vel, omega, a, b)
    # dispatched here, as in sequential_impulses.sweep_manifolds
    if count < 2:
        p, _ = update_contact(R1, I1, first, p0)
    else:
        p, _ = update_points(R1, M1, MI1, m, first, count, p0, shares)
    store_pair(vel, omega, a, b, p)
    return max(_point_change(p0, p, 0, lever), _point_change(p0, p, 6, lever))


@njit(cache=True, inline="always")
def _settle(one_sided, vel, omega, passes, tolerance, store):
    """Sweeps over one body's one-sided manifolds (its supports immovable), up
    to `passes`, until a sweep changes no contact-point velocity by more
    than `tolerance` (m/s; ≤ 0: all passes): the body then rests on the
    layer below, solved to convergence (a partly converged box on four
    corners tilts). The test is on velocities, not impulses: four coplanar
    corners share a load in many ways, so their impulses can keep trading
    while the body's velocity has long settled. It also stops when its
    change has stalled (STALL)."""
    R1, I1, M1, MI1 = one_sided
    levers, shares = take(store, len(MI1)), face_shares(R1, MI1, take(store, len(R1)))
    for m in range(len(MI1)):
        levers[m] = _lever(R1, MI1[m, FIRST], MI1[m, COUNT])
    last = earlier = math.inf
    for _ in range(passes):
        change = 0.0
        for m in range(len(MI1)):
            change = max(change, _update(R1, I1, M1, MI1, m, vel, omega, levers[m], shares))
        if tolerance > 0.0 and change < tolerance:
            break
        if change > STALL * earlier:
            break
        earlier, last = last, change


@njit(cache=True, inline="always")
def _scatter_impulses(R, M, MI, order, one_sided):
    """The settled λ of the compact rows and anchors (_one_sided of `order`)
    back into R and M."""
    R1, _, M1, MI1 = one_sided
    for m in range(len(order)):
        k = order[m]
        for j in range(MI[k, COUNT]):
            for r in range(3):
                R[MI[k, FIRST] + j, LAM + r] = R1[MI1[m, FIRST] + j, LAM + r]
        if MI[k, COUNT] < 2:
            continue                     # no anchor (_one_sided)
        for r in range(3):
            M[k, M_LAM + r] = M1[m, M_LAM + r]


@njit(cache=True, inline="always")
def _kinetic_energy(i, vel, omega, masses):
    """½ m |v|² + ½ ω·I ω of body i (COURSE.md 3; masses = (1/m, body-frame
    diagonal I⁻¹, orientations); 1/m = 0: immovable, no energy)."""
    inv_mass, inv_inertia, quat = masses
    if not inv_mass[i] > 0.0:
        return 0.0
    e = 0.5 * (vel[i, 0] ** 2 + vel[i, 1] ** 2 + vel[i, 2] ** 2) / inv_mass[i]
    w = rotate_inverse_one(row4(quat, i), (omega[i, 0], omega[i, 1], omega[i, 2]))
    for j in range(3):
        if inv_inertia[i, j] > 0.0:
            e += 0.5 * w[j] * w[j] / inv_inertia[i, j]
    return e


@njit(cache=True, inline="always")
def _run_end(uppers, s):
    """The end of the run from s of manifolds holding up the same body
    (uppers: each one's body, _upward_order)."""
    t = s + 1
    while t < len(uppers) and uppers[t] == uppers[s]:
        t += 1
    return t


@njit(cache=True, inline="always")
def _swap(T, i, at, saved, j, put_back):
    """saved[j] ← T[i, at:at + 3], or back (put_back)."""
    for r in range(3):
        if put_back:
            T[i, at + r] = saved[j, r]
        else:
            saved[j, r] = T[i, at + r]


@njit(cache=True, inline="always")
def _lambdas(R, M, MI, ms, saved, put_back):
    """The λ of manifolds ms's rows and anchors into `saved` ((rows + anchors,
    3): each manifold's rows, then its anchor), or back from it (put_back).
    Returns the entries used."""
    j = 0
    for k in ms:
        first, count = MI[k, FIRST], MI[k, COUNT]
        for c in range(first, first + count):
            _swap(R, c, LAM, saved, j, put_back)
            j += 1
        if count >= 2:                   # a single point has no anchor (_one_sided)
            _swap(M, k, M_LAM, saved, j, put_back)
            j += 1
    return j


@njit(cache=True, inline="always")
def _settle_body(tables, ms, body, vel, omega, passes, tolerance, layer, masses, resting,
                 store):
    """Body `body` settled on its manifolds ms with the layer below: at once
    when it rests on them (resting_block.py, on the contact tables
    themselves: it moves the upper body alone), else by sweeps (_settle) on
    one-sided copies of them, their λ put back after. The copies are given
    back to the scratch when done (scratch.rewind): the next body's reuse
    the same memory, still in cache."""
    R, I, M, MI = tables
    block, ws = resting
    # a single point is never taken (resting_block._takes_part): not called for one
    if (block and len(ms) <= MANIFOLDS and MI[ms[0], COUNT] >= 2
            and settle_resting(tables, ms, body, vel, omega, masses, tolerance, ws)):
        return
    mark = cursor(store)
    one_sided = _one_sided(R, I, M, MI, layer, ms, store)
    _frozen_masses(one_sided, take_rows(store, 3, 3))
    _settle(one_sided, vel, omega, passes, tolerance, store)
    _scatter_impulses(R, M, MI, ms, one_sided)
    rewind(store, mark)


@njit(cache=True)
def _settle_layer(tables, ms, uppers, vel, omega, passes, tolerance, layer, masses, resting,
                  store):
    """One layer (manifolds ms, in runs of one upper body, uppers: _upward_order)
    settled body by body (_settle_body: with the layer below immovable, its
    bodies share no movable one), undone if it gave the layer's bodies
    kinetic energy: resting on what holds it removes approach and slip, so
    a layer that gains energy was made to follow a support it cannot
    follow (a box on two boxes moving apart, a box turning under another):
    its velocities and λ are put back (each body's saved just before it is
    settled, while its rows are in cache)."""
    R, I, M, MI = tables
    bodies, saved = take_ints(store, len(ms)), take_rows(store, len(ms), 6)
    lam = take_rows(store, len(ms) + _row_count(MI, ms), 3)
    before = after = 0.0
    s = j = count = 0
    while s < len(ms):
        t = _run_end(uppers, s)
        body = uppers[s]
        bodies[count] = body
        for i in range(3):
            saved[count, i], saved[count, 3 + i] = vel[body, i], omega[body, i]
        count += 1
        j += _lambdas(R, M, MI, ms[s:t], lam[j:], False)
        before += _kinetic_energy(body, vel, omega, masses)
        _settle_body(tables, ms[s:t], body, vel, omega, passes, tolerance, layer, masses,
                     resting, store)
        after += _kinetic_energy(body, vel, omega, masses)
        s = t
    if after > before * (1.0 + GAIN) + 1e-300:
        for k in range(count):
            for i in range(3):
                vel[bodies[k], i], omega[bodies[k], i] = saved[k, i], saved[k, 3 + i]
        _lambdas(R, M, MI, ms, lam, True)


@njit(cache=True, inline="always")
def shock_sweep(R, I, M, MI, vel, omega, n, passes, tolerance, masses, block, unsettled, store):
    """The ordered one-sided sweep (module docstring), layer after layer from
    the ground up, each settled in turn (`_settle_layer`; with `block`, a
    body resting on one support through three or more points at once,
    resting_block.py), over the groups of bodies the sweeps left unsettled
    (leave_out_settled); the rows' and anchors' λ updated in place. Returns
    (the number of manifolds visited, the bodies' layers: only a body with
    a layer from 1 to below UNREACHED may have had its velocity changed)."""
    unsettled_count = _unsettled_count(MI, unsettled)
    if unsettled_count == 0:
        return 0, take_ints(store, 0)
    layer, graph = support_layers(R, I, MI, n, store)
    # every reached body has a manifold: with all of them unsettled, none is left out
    if (unsettled_count < len(MI)
            and leave_out_settled(I, MI, layer, graph, unsettled, store) == 0):
        return 0, layer
    order, top, uppers = _upward_order(I, MI, layer, store)
    resting = (block, take_rows(store, WS_SHAPE[0], WS_SHAPE[1]))
    g = 0
    while g < len(order):
        e = g + 1
        while e < len(order) and top[e] == top[g]:
            e += 1
        _settle_layer((R, I, M, MI), order[g:e], uppers[g:e], vel, omega, passes, tolerance,
                      layer, masses, resting, store)
        g = e
    return len(order), layer
