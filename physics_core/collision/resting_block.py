"""A body resting on frozen supports through manifolds of two or more points
(three or more in all), settled in one solve instead of sweep after sweep
(COURSE.md 5, resting contact; shock_propagation.py calls it).

In the shock-propagation sweep the lower layer is immovable, so a body
and its manifolds with the layer below are a small problem of their own:
its normal rows (u_n = the row's bias while it pushes) and each manifold's
friction anchor (no slip and no twist while friction holds) are conditions
on its six velocities, seven for a box on one face. Sequential impulses reach their
solution at about 0.7 a sweep on four coplanar corners, so a pyramid's
ground layer or a column of cubes ran all its sweeps. Here the conditions
are solved together:

    J Δq = t − u          (J: the rows' velocity per unit of the body's
                            velocity q = (v, ω), t their targets, u now)
    Δq = (JᵀJ)⁻¹ Jᵀ (t − u)                 the least-squares change, exact when the
                                            seven are consistent (a rigid support)
    Jᵀ x = M Δq,  x = J (JᵀJ)⁻¹ M Δq        the impulses along the rows that make it,
                                            the least change of the impulses

with M the body's mass matrix (m, and I_w = R diag(I) Rᵀ). Four coplanar
points of one manifold can share a load in a line of ways (x + t z,
Jᵀ z = 0): when the least change leaves a point pulling, x is moved along
z to the nearest t where every point pushes. The result is the one the
sweeps converge to when every point keeps pushing, friction holds and the
supports move as one rigid whole: so it is taken only then (every normal
impulse ≥ 0, each anchor's tangential impulse within μ_s Σλ_n and its
twist within μ_s Σλ_n r̄, manifold_friction.py, and the conditions met to
RESIDUAL); otherwise (a single point, a kinetic manifold, supports moving
apart, a singular JᵀJ) nothing is changed and the sweeps solve it as before.
"""
import math

from numba import njit

from ..quaternion import rotate_inverse_one, rotate_one, row4
from .contact_build import row_velocity
from .contact_layout import ARM_A, ARM_B, BIAS, BODY_A, BODY_B, DIR, LAM, STRIDE
from .manifold_friction import AA, AB, COUNT, FIRST, L, M_LAM, M_MU_S, M_SLIDING, RADIUS
from .pair_velocity import load_pair, pair_impulse, store_pair

# The steps of settle_resting are inlined into it (inline="always"): a call
# passes the workspace and the row tables field by field, and a solve makes
# about a dozen such calls (inlined together with the shock sweep's row
# freezing: the pyramid of 100's step 0.95x)
MANIFOLDS = 4         # a body's manifolds solved together at most
ROWS = 7 * MANIFOLDS  # four normal rows and an anchor's three each
SINGULAR = 1e-12      # a Cholesky pivot below this × the largest diagonal: JᵀJ is singular
RESIDUAL = 100.0      # × the settle tolerance: a body on several supports must meet its
                      # conditions to the solve's own velocity tolerance, or they do not
                      # move as one (they part)
FAC, VEC, DQ, NUL, TMP = ROWS, ROWS + 6, ROWS + 7, ROWS + 8, ROWS + 9
WS_SHAPE = (ROWS + 10, ROWS)   # the workspace: J (rows 0..ROWS-1, 6 columns), JᵀJ's factor
                               # (FAC..FAC+5), t − u then x (VEC), Δq (DQ), z (NUL), scratch (TMP)


@njit(cache=True, inline="always")
def _manifold_rows(R, I, M, MI, m, vel, omega, upper_is_b, ws, j):
    """J and t − u of manifold m's rows from row j of the workspace; the next row."""
    first, count = MI[m, FIRST], MI[m, COUNT]
    a, b = I[first, BODY_A], I[first, BODY_B]
    sign = 1.0 if upper_is_b else -1.0
    arm, anchor_arm = (ARM_B, AB) if upper_is_b else (ARM_A, AA)
    for c in range(first, first + count):
        for i in range(3):
            ws[j, i] = sign * R[c, DIR + i]
            ws[j, 3 + i] = sign * R[c, arm + i]
        ws[VEC, j] = R[c, BIAS] - row_velocity(R, c, 0, a, b, vel, omega)
        j += 1
    for r in range(3):
        for i in range(3):
            ws[j, i] = sign * M[m, L + STRIDE * r + i]
            ws[j, 3 + i] = sign * M[m, anchor_arm + STRIDE * r + i]
        ws[VEC, j] = -row_velocity(M, m, r, a, b, vel, omega)    # the rows' layout
        j += 1
    return j


@njit(cache=True, inline="always")
def _factor(ws, k):
    """JᵀJ of the k rows into ws[FAC:FAC + 6], Cholesky-factored in place
    (lower), each pivot's reciprocal on the diagonal: the solves multiply by
    it (a body's solve chained some 40 divisions, each waiting on the one
    before: 15 in the factor and 12 in each of its two or three
    substitutions); False when a pivot is not clearly positive (the rows do
    not fix all six velocities: collinear points)."""
    top = 0.0
    for p in range(6):
        for q in range(p + 1):          # the factorisation reads the lower triangle only
            s = 0.0
            for j in range(k):
                s += ws[j, p] * ws[j, q]
            ws[FAC + p, q] = s
        top = max(top, ws[FAC + p, p])
    for p in range(6):
        d = ws[FAC + p, p]
        for s in range(p):
            d -= ws[FAC + p, s] * ws[FAC + p, s]
        if not d > SINGULAR * top:
            return False
        inv = 1.0 / math.sqrt(d)
        ws[FAC + p, p] = inv
        for q in range(p + 1, 6):
            e = ws[FAC + q, p]
            for s in range(p):
                e -= ws[FAC + q, s] * ws[FAC + p, s]
            ws[FAC + q, p] = e * inv
    return True


@njit(cache=True, inline="always")
def _solve(ws, y):
    """y (6,) ← (JᵀJ)⁻¹ y with the factor in ws[FAC:FAC + 6] (_factor)."""
    for p in range(6):
        s = y[p]
        for q in range(p):
            s -= ws[FAC + p, q] * y[q]
        y[p] = s * ws[FAC + p, p]
    for p in range(5, -1, -1):
        s = y[p]
        for q in range(p + 1, 6):
            s -= ws[FAC + q, p] * y[q]
        y[p] = s * ws[FAC + p, p]


@njit(cache=True, inline="always")
def _velocity_change(ws, k, tolerance):
    """Δq = (JᵀJ)⁻¹ Jᵀ (t − u) into ws[DQ, :6]; False if it leaves some
    condition unmet by more than `tolerance` (m/s: the supports part)."""
    y = ws[DQ]
    for p in range(6):
        s = 0.0
        for j in range(k):
            s += ws[j, p] * ws[VEC, j]
        y[p] = s
    _solve(ws, y)
    for j in range(k):
        r = -ws[VEC, j]
        for p in range(6):
            r += ws[j, p] * y[p]
        if not abs(r) <= tolerance:
            return False
    return True


@njit(cache=True, inline="always")
def _momentum(ws, body, masses):
    """ws[DQ, :6] ← M Δq: m Δv and I_w Δω (I_w = R diag(I) Rᵀ, COURSE.md 3);
    False if the body has an infinite mass or moment."""
    inv_mass, inv_inertia, quat = masses
    if not inv_mass[body] > 0.0:
        return False
    for i in range(3):
        if not inv_inertia[body, i] > 0.0:
            return False
    q = row4(quat, body)
    w = rotate_inverse_one(q, (ws[DQ, 3], ws[DQ, 4], ws[DQ, 5]))
    lw = rotate_one(q, (w[0] / inv_inertia[body, 0], w[1] / inv_inertia[body, 1],
                        w[2] / inv_inertia[body, 2]))
    for i in range(3):
        ws[DQ, i] = ws[DQ, i] / inv_mass[body]
        ws[DQ, 3 + i] = lw[i]
    return True


@njit(cache=True, inline="always")
def _impulses(ws, k):
    """x = J (JᵀJ)⁻¹ M Δq into ws[VEC, :k] (M Δq in ws[DQ, :6], overwritten)."""
    y = ws[DQ]
    _solve(ws, y)
    for j in range(k):
        s = 0.0
        for p in range(6):
            s += ws[j, p] * y[p]
        ws[VEC, j] = s


@njit(cache=True)
def _null_impulse(ws, k, e):
    """ws[NUL, :k] ← the part of unit impulse e (on row e) that changes no
    velocity of the body, z = e − J (JᵀJ)⁻¹ Jᵀ e: the rows' impulses can
    move along it freely (four coplanar points share a load in a line of
    ways). Returns |z|²."""
    y = ws[TMP]
    for p in range(6):
        y[p] = ws[e, p]
    _solve(ws, y)
    size = 0.0
    for j in range(k):
        z = (1.0 if j == e else 0.0)
        for p in range(6):
            z -= ws[j, p] * y[p]
        ws[NUL, j] = z
        size += z * z
    return size


@njit(cache=True)
def _shift_bounds(R, first, count, ws):
    """(lo, hi, row at lo, row at hi): the moves t along ws[NUL] that keep every
    normal impulse ≥ 0 (lo > hi: none does)."""
    lo, hi, at_lo, at_hi = -math.inf, math.inf, -1, -1
    for j in range(count):
        lam, z = R[first + j, LAM] + ws[VEC, j], ws[NUL, j]
        if z > 0.0 and -lam / z > lo:
            lo, at_lo = -lam / z, j
        elif z < 0.0 and -lam / z < hi:
            hi, at_hi = -lam / z, j
        elif z == 0.0 and lam < 0.0:
            return math.inf, -math.inf, -1, -1
    return lo, hi, at_lo, at_hi


@njit(cache=True)
def _push_everywhere(R, first, count, ws, k):
    """Moves the impulses ws[VEC] along the load-sharing direction of a single
    manifold of four points (its only one) to the nearest point where every
    normal impulse is ≥ 0; False if there is none."""
    if k != 7 or _null_impulse(ws, k, 0) < 1e-12:
        return False
    lo, hi, at_lo, at_hi = _shift_bounds(R, first, count, ws)
    if not lo <= hi:
        return False
    t, at = (lo, at_lo) if lo > 0.0 else ((hi, at_hi) if hi < 0.0 else (0.0, -1))
    for j in range(k):
        ws[VEC, j] += t * ws[NUL, j]
    if at >= 0:
        ws[VEC, at] = -R[first + at, LAM]       # the row that bounds the move ends at exactly 0
    return True


@njit(cache=True, inline="always")
def _holds(R, M, MI, m, ws, j):
    """Manifold m's points (workspace rows from j) still push and its friction
    holds after the impulses ws[VEC]."""
    first, count = MI[m, FIRST], MI[m, COUNT]
    ln = 0.0
    for i in range(count):
        lam = R[first + i, LAM] + ws[VEC, j + i]
        if not lam >= 0.0:
            return False
        ln += lam
    t0 = M[m, M_LAM] + ws[VEC, j + count]
    t1 = M[m, M_LAM + 1] + ws[VEC, j + count + 1]
    twist = M[m, M_LAM + 2] + ws[VEC, j + count + 2]
    lim = M[m, M_MU_S] * ln
    return t0 * t0 + t1 * t1 <= lim * lim and abs(twist) <= lim * M[m, RADIUS]


@njit(cache=True, inline="always")
def _all_hold(R, M, MI, ms, ws):
    j = 0
    for m in ms:
        if not _holds(R, M, MI, m, ws, j):
            return False
        j += MI[m, COUNT] + 3
    return True


@njit(cache=True, inline="always")
def _apply(tables, ms, upper, vel, omega, ws):
    """The impulses ws[VEC] along the manifolds' rows, added to their λ; only
    the upper body's velocities change (the support is frozen: its side of
    each row takes no impulse)."""
    R, I, M, MI = tables
    j = 0
    for m in ms:
        first, count = MI[m, FIRST], MI[m, COUNT]
        a, b = I[first, BODY_A], I[first, BODY_B]
        p = load_pair(vel, omega, a, b)
        for c in range(first, first + count):
            R[c, LAM] += ws[VEC, j]
            p = pair_impulse(R, c, 0, ws[VEC, j], p)
            j += 1
        for r in range(3):
            M[m, M_LAM + r] += ws[VEC, j]
            p = pair_impulse(M, m, r, ws[VEC, j], p)
            j += 1
        o = 6 if b == upper else 0
        for i in range(3):
            vel[upper, i], omega[upper, i] = p[o + i], p[o + 3 + i]


@njit(cache=True, inline="always")
def _takes_part(I, MI, m, upper):
    """(whether manifold m may take part: two points or more, static
    friction, `upper` one of its bodies; whether `upper` is its side b)."""
    first, count = MI[m, FIRST], MI[m, COUNT]
    upper_is_b = I[first, BODY_B] == upper
    ok = count >= 2 and MI[m, M_SLIDING] == 0 and (upper_is_b or I[first, BODY_A] == upper)
    return ok, upper_is_b


@njit(cache=True, inline="always")
def _rows(tables, ms, upper, vel, omega, ws):
    """The row count of the manifolds ms of body `upper`, their rows in the
    workspace; -1 when one of them may not take part."""
    R, I, M, MI = tables
    j = 0
    for m in ms:
        ok, upper_is_b = _takes_part(I, MI, m, upper)
        if not ok or j + MI[m, COUNT] + 3 > ROWS:
            return -1
        j = _manifold_rows(R, I, M, MI, m, vel, omega, upper_is_b, ws, j)
    return j


@njit(cache=True)
def settle_resting(tables, ms, upper, vel, omega, masses, tolerance, ws):
    """The manifolds ms of the contact tables (R, I, M, MI) (all those of body
    `upper` with the layer below, whose bodies are frozen: no impulse
    reaches them) solved at once when the body rests on them (module
    docstring), `tolerance` the settle's (m/s); True if they were, False
    with nothing changed."""
    R, I, M, MI = tables
    k = _rows(tables, ms, upper, vel, omega, ws)
    if k < 0 or not _factor(ws, k):
        return False
    # one face's seven conditions are consistent but for the touch shift of its
    # anchor (contact_build.contact_arms: 2 s |ω| of a turning support); several
    # supports are consistent only while they move as one
    residual = RESIDUAL * tolerance if len(ms) > 1 else math.inf
    if not _velocity_change(ws, k, residual) or not _momentum(ws, upper, masses):
        return False
    _impulses(ws, k)
    if not _all_hold(R, M, MI, ms, ws):
        first, count = MI[ms[0], FIRST], MI[ms[0], COUNT]
        if not (_push_everywhere(R, first, count, ws, k) and _all_hold(R, M, MI, ms, ws)):
            return False
    _apply(tables, ms, upper, vel, omega, ws)
    return True
