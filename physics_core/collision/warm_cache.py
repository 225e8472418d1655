"""Warm starting: a contact starts each substep with last substep's impulses.

Matched by Manifold key (pair and feature), both lists in ascending key
order, by one merge pass. The normal impulse is reused as it was; the
friction impulse is kept as a world vector and projected on the new tangent
basis, so it survives a change of basis. The contact's slip speed after the
solve is kept too: it decides static or kinetic friction next substep
(COURSE.md 2 and 5: held while slipping slower than `static_friction_speed`,
μ_s; sliding with μ_k otherwise). A new contact has no slip of its own yet:
it slides if its surfaces slip past each other faster than that at the
start of the substep, before the forces of this substep act (a box that
lands or is launched sliding is already sliding and takes μ_k from its
first substep; one set down at rest holds with μ_s, even on an incline
where this substep's gravity has already given it g sin θ h of slip). The
restitution pass's extra push is not kept: it belongs to one impact, not to
the load.
"""
import math

import numpy as np
from numba import njit

from .contact_build import row_velocity
from .contact_data import WARM_COLS, WARM_FRICTION, WARM_NORMAL, WARM_SLIP
from .contact_layout import BODY_A, BODY_B, DIR, LAM, MU, MU_K, MU_S, SLIDING, STRIDE


@njit(cache=True, inline="always")
def start_slip(R, I, c, vel0, omega0):
    """|u_t| of row c at the start-of-substep velocities vel0, omega0."""
    a, b = I[c, BODY_A], I[c, BODY_B]
    u1 = row_velocity(R, c, 1, a, b, vel0, omega0)
    u2 = row_velocity(R, c, 2, a, b, vel0, omega0)
    return math.sqrt(u1 * u1 + u2 * u2)


@njit(cache=True)
def load_warm(R, I, key, old_key, old, fraction, static_speed, vel0, omega0):
    """λ of the rows whose key was seen last substep (× fraction), and each
    row's friction regime: from its last slip speed, or for a new contact
    from its slip at the start-of-substep velocities vel0, omega0. old
    (m, 5): normal impulse, friction impulse (world vector), slip speed per
    old key."""
    j = 0
    m = len(old_key)
    for c in range(len(key)):
        while j < m and old_key[j] < key[c]:
            j += 1
        slip = np.nan
        if j < m and old_key[j] == key[c]:
            slip = old[j, WARM_SLIP]
            if fraction > 0.0:
                f0, f1, f2 = old[j, WARM_FRICTION], old[j, WARM_FRICTION + 1], old[j, WARM_FRICTION + 2]
                R[c, LAM] = old[j, WARM_NORMAL] * fraction
                t1, t2 = DIR + STRIDE, DIR + 2 * STRIDE
                R[c, LAM + 1] = (f0 * R[c, t1] + f1 * R[c, t1 + 1] + f2 * R[c, t1 + 2]) * fraction
                R[c, LAM + 2] = (f0 * R[c, t2] + f1 * R[c, t2 + 1] + f2 * R[c, t2 + 2]) * fraction
        if slip != slip:                   # a new contact
            slip = start_slip(R, I, c, vel0, omega0)
        sliding = slip > static_speed
        I[c, SLIDING] = 1 if sliding else 0
        R[c, MU] = R[c, MU_K] if sliding else R[c, MU_S]


@njit(cache=True, inline="always")
def cached(cache_keys, cache_values):
    """(keys, values) of the contacts kept: views of the cache's arrays, the
    keys' first element holding their count (contact_data.new_warm_cache)."""
    keys, values = cache_keys[0], cache_values[0]
    return keys[1:keys[0] + 1], values[:keys[0]]


@njit(cache=True, inline="always")
def warm_load(R, I, key, cache_keys, cache_values, fraction, static_speed, vel0, omega0):
    old_key, old = cached(cache_keys, cache_values)
    load_warm(R, I, key, old_key, old, fraction, static_speed, vel0, omega0)


@njit(cache=True, inline="always")
def warm_store(cache_keys, cache_values, key, R, friction, slip):
    """Keep this substep's impulses, friction vectors and slip speeds by key in
    the cache's arrays (grown by doubling; the old entries were read by
    warm_load already, so they are overwritten), their count first."""
    keys, values = _buffers(cache_keys, cache_values, len(key))
    keys[0] = len(key)
    for c in range(len(key)):
        keys[1 + c] = key[c]
        values[c, WARM_NORMAL] = R[c, LAM]
        for i in range(3):
            values[c, WARM_FRICTION + i] = friction[c, i]
        values[c, WARM_SLIP] = slip[c]


@njit(cache=True, inline="always")
def _buffers(cache_keys, cache_values, k):
    """The cache's arrays, replaced by ones of at least 2× the rows when they
    hold fewer than k (a typed list's item is read and written through
    numba's C helpers, about 30 ns each: once each a substep, not more)."""
    keys, values = cache_keys[0], cache_values[0]
    if len(values) < k:
        size = max(k, 2 * len(values))
        keys, values = np.empty(size + 1, np.int64), np.empty((size, WARM_COLS))
        cache_keys[0] = keys
        cache_values[0] = values
    return keys, values


@njit(cache=True, inline="always")
def warm_clear(cache_keys, cache_values):
    keys = cache_keys[0]
    keys[0] = 0


@njit(cache=True)
def remap_keys(key, n_old, n_new, new_index, slots):
    """Feature keys (manifold.py: (min·n + max)·SLOTS + slot) re-encoded after a
    change of the body set: new_index[old body] = its new index, -1 if removed.
    Returns (keys, kept) with kept[i] False for a contact of a removed body.
    The surviving bodies keep their order, so ascending keys stay ascending."""
    out = np.empty(len(key), np.int64)
    kept = np.zeros(len(key), np.bool_)
    for i in range(len(key)):
        slot = key[i] % slots
        pair = key[i] // slots
        lo, hi = new_index[pair // n_old], new_index[pair % n_old]
        if lo >= 0 and hi >= 0:
            out[i] = (min(lo, hi) * n_new + max(lo, hi)) * slots + slot
            kept[i] = True
    return out, kept


def remap_warm_cache(cache_keys, cache_values, n_old, n_new, new_index, slots):
    """The cache for the same contacts after a change of the body set."""
    old_key, old = cached(cache_keys, cache_values)
    key, kept = remap_keys(old_key, n_old, n_new, new_index, slots)
    cache_keys[0] = np.concatenate(([np.int64(kept.sum())], key[kept]))
    cache_values[0] = np.ascontiguousarray(old[kept])
