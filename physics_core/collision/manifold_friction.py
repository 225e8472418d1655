"""Friction of a whole manifold: one anchor at the centre of its points
(COURSE.md 2 and 5, static and kinetic friction).

The course's static friction holds a contact while the tangential force it
needs is within μ_s times its normal force. Solved point by point, a box's
four corners each take the impulse that stops its own slip; with the
rotational coupling of each corner those impulses point partly sideways
and cancel in pairs, so the box slid at 0.91–0.94 μ_s. Here a manifold of
two or more points (rows of one body pair, contiguous in key order) has one
friction anchor at the centroid c of its points, three constraint rows:

    r = 0, 1  the tangents t1, t2 at c:  u_r = t_r·(v_b − v_a) + (r_b × t_r)·ω_b − (r_a × t_r)·ω_a
    r = 2     the twist about n:         u_2 = n·(ω_b − ω_a)

(r_a = c − x_a + s n, r_b = c − x_b − s n, s the points' mean shift to
where the surfaces touched, contact_build.contact_arms), solved together
with their 3×3 effective mass W (W_rs = u_r's change per unit impulse
along s). The tangential impulse is capped by μ Σλ_n over the whole
manifold (μ_s while it holds, μ_k against the slip once it slides) and
the twist by μ Σλ_n r̄, r̄ the mean distance of the points from c. The
points keep their normal rows.

`M` (m, MCOL) float and `MI` (m, MICOL) int hold one row per manifold
(single-point ones too, so the solver loops over manifolds); a manifold is
anchored when MI[m, COUNT] ≥ 2.
"""
import math

from numba import njit

from .contact_build import start_separation, tangent_world, touch_shift
from .kinetic_bound import kinetic_bound
from .contact_layout import (ARM_A, ARM_B, BODY_A, BODY_B, DEPTH, DIR, INV_MASS_A, INV_MASS_B, LAM,
                             MU_K, MU_S, SLIDING, STRIDE, TURN_A, TURN_B, U0)
from .pair_velocity import load_pair, pair_impulses, pair_velocity, store_pair
from .scratch import take, take_int_rows, take_rows

# float columns: per row r (3): linear direction L, angular parts for a and b,
# I_w⁻¹ times them, and the bodies' inverse masses, in the contact rows'
# columns (pair_velocity.py updates both tables); then W⁻¹ (3×3), μ_s, μ_k,
# r̄, λ (3)
L, AA, AB, TA, TB, IMA, IMB = DIR, ARM_A, ARM_B, TURN_A, TURN_B, INV_MASS_A, INV_MASS_B
W_INV, M_MU_S, M_MU_K, RADIUS, M_LAM, MCOL = 53, 62, 63, 64, 65, 68
# int columns: first row, number of rows, sliding (kinetic friction this substep)
FIRST, COUNT, M_SLIDING, MICOL = 0, 1, 2, 3
_TINY = 1e-300


@njit(cache=True)
def _starts_run(I, c):
    """Whether row c begins a manifold: the first row, or a new body pair."""
    return c == 0 or I[c, BODY_A] != I[c - 1, BODY_A] or I[c, BODY_B] != I[c - 1, BODY_B]


@njit(cache=True)
def manifold_ranges(I, store):
    """MI with the first row and row count of every run of rows of one pair
    (in the substep's scratch, scratch.py)."""
    m = 0
    for c in range(len(I)):
        m += _starts_run(I, c)
    MI = take_int_rows(store, m, MICOL)
    MI[:] = 0
    k = -1
    for c in range(len(I)):
        if _starts_run(I, c):
            k += 1
            MI[k, FIRST] = c
        MI[k, COUNT] += 1
        MI[k, M_SLIDING] |= I[c, SLIDING]
    return MI


@njit(cache=True, inline="always")
def _centre(point, first, count):
    """Centroid of the manifold's points and their mean distance from it."""
    cx = cy = cz = 0.0
    for c in range(first, first + count):
        cx += point[c, 0]
        cy += point[c, 1]
        cz += point[c, 2]
    cx, cy, cz = cx / count, cy / count, cz / count
    rbar = 0.0
    for c in range(first, first + count):
        rbar += math.sqrt((point[c, 0] - cx) ** 2 + (point[c, 1] - cy) ** 2
                          + (point[c, 2] - cz) ** 2)
    return cx, cy, cz, rbar / count


@njit(cache=True, inline="always")
def _shift(R, I, first, count, toi, h):
    """The mean of the points' touch shifts (contact_build.touch_shift)."""
    s = 0.0
    for c in range(first, first + count):
        rewound = toi[I[c, BODY_A]] >= 0.0 or toi[I[c, BODY_B]] >= 0.0
        s += touch_shift(R[c, DEPTH], start_separation(R[c, DEPTH], R[c, U0], rewound, h))
    return s / count


@njit(cache=True, inline="always")
def _body_parts(M, k, ang, turn, normal, rx, ry, rz, iw, body):
    """Angular parts of one body for the three rows: r × t1, r × t2, n
    (iw[body]: its I_w⁻¹, row-major)."""
    for r in range(3):
        dx, dy, dz = M[k, L + STRIDE * r], M[k, L + STRIDE * r + 1], M[k, L + STRIDE * r + 2]
        if r == 2:
            cx, cy, cz = normal[0], normal[1], normal[2]
        else:
            cx, cy, cz = ry * dz - rz * dy, rz * dx - rx * dz, rx * dy - ry * dx
        o = ang + STRIDE * r
        M[k, o], M[k, o + 1], M[k, o + 2] = cx, cy, cz
        o = turn + STRIDE * r
        for i in range(3):
            M[k, o + i] = iw[body, 3 * i] * cx + iw[body, 3 * i + 1] * cy + iw[body, 3 * i + 2] * cz


@njit(cache=True, inline="always")
def _coupling(M, k, r, s):
    ll = 0.0
    wa = 0.0
    wb = 0.0
    for i in range(3):
        ll += M[k, L + STRIDE * r + i] * M[k, L + STRIDE * s + i]
        wa += M[k, AA + STRIDE * r + i] * M[k, TA + STRIDE * s + i]
        wb += M[k, AB + STRIDE * r + i] * M[k, TB + STRIDE * s + i]
    return (M[k, IMA] + M[k, IMB]) * ll + wa + wb


@njit(cache=True, inline="always")
def _invert(M, k, w):
    """W⁻¹ of manifold k (adjugate over determinant; W is symmetric positive);
    w: (3, 3) scratch."""
    for r in range(3):
        for s in range(3):
            w[r, s] = _coupling(M, k, r, s)
    det = (w[0, 0] * (w[1, 1] * w[2, 2] - w[1, 2] * w[2, 1])
           - w[0, 1] * (w[1, 0] * w[2, 2] - w[1, 2] * w[2, 0])
           + w[0, 2] * (w[1, 0] * w[2, 1] - w[1, 1] * w[2, 0]))
    inv = 1.0 / (det if abs(det) > 1e-30 else 1e-30)
    for r in range(3):
        for s in range(3):
            r1, r2, s1, s2 = (s + 1) % 3, (s + 2) % 3, (r + 1) % 3, (r + 2) % 3
            M[k, W_INV + 3 * r + s] = (w[r1, s1] * w[r2, s2] - w[r1, s2] * w[r2, s1]) * inv


@njit(cache=True, inline="always")
def anchor_rows(R, I, point, pos, iw, toi, h, store):
    """(M, MI) of the contact rows: every manifold's range, and the anchor
    rows of those with two or more points (the rows' own friction zeroed);
    toi, h: the bodies' times of impact and the substep (the touch shift).
    A single point's M row is left unwritten: every reader of M takes the
    manifolds of two or more points only."""
    MI = manifold_ranges(I, store)
    M = take_rows(store, len(MI), MCOL)
    w = take_rows(store, 3, 3)
    n = take(store, 3)
    for k in range(len(MI)):
        first, count = MI[k, FIRST], MI[k, COUNT]
        if count < 2:
            continue
        a, b = I[first, BODY_A], I[first, BODY_B]
        cx, cy, cz, rbar = _centre(point, first, count)
        s = _shift(R, I, first, count, toi, h)
        for r in range(3):          # the anchor's t1, t2: the rows'; its twist has no linear part
            for i in range(3):
                M[k, L + STRIDE * r + i] = R[first, DIR + STRIDE * (r + 1) + i] if r < 2 else 0.0
        for i in range(3):
            n[i] = R[first, DIR + i]
        M[k, IMA], M[k, IMB] = R[first, INV_MASS_A], R[first, INV_MASS_B]
        _body_parts(M, k, AA, TA, n, cx - pos[a, 0] + s * n[0], cy - pos[a, 1] + s * n[1],
                    cz - pos[a, 2] + s * n[2], iw, a)
        _body_parts(M, k, AB, TB, n, cx - pos[b, 0] - s * n[0], cy - pos[b, 1] - s * n[1],
                    cz - pos[b, 2] - s * n[2], iw, b)
        _invert(M, k, w)
        M[k, M_MU_S], M[k, M_MU_K], M[k, RADIUS] = R[first, MU_S], R[first, MU_K], rbar
        M[k, M_LAM], M[k, M_LAM + 1], M[k, M_LAM + 2] = 0.0, 0.0, 0.0   # every other column is set
        _take_row_friction(R, M, k, first, count)
    return M, MI


@njit(cache=True)
def _take_row_friction(R, M, k, first, count):
    """The rows' warm-started friction impulses (world vectors) summed into the
    anchor's tangential λ; the rows keep none of their own."""
    for c in range(first, first + count):
        for r in range(2):
            lam = 0.0
            for i in range(3):
                f = tangent_world(R, c, R[c, LAM + 1], R[c, LAM + 2], i)
                lam += f * M[k, L + STRIDE * r + i]
            M[k, M_LAM + r] += lam
        R[c, LAM + 1] = 0.0
        R[c, LAM + 2] = 0.0


@njit(cache=True, inline="always")
def anchor_warm_start(M, MI, I, vel, omega):
    """The anchors' warm-started tangential impulses applied (the table has
    the rows' column layout: pair_velocity.py, as for the rows)."""
    for k in range(len(MI)):
        if MI[k, COUNT] >= 2:
            a, b = I[MI[k, FIRST], BODY_A], I[MI[k, FIRST], BODY_B]
            l0, l1 = M[k, M_LAM], M[k, M_LAM + 1]
            if l0 != 0.0 or l1 != 0.0:
                p = pair_impulses(M, k, l0, l1, 0.0, load_pair(vel, omega, a, b))
                store_pair(vel, omega, a, b, p)


@njit(cache=True, inline="always")
def anchor_stopping(M, k, p):
    """W⁻¹ u at manifold k's anchor on its pair's velocities p, u = (u_t1,
    u_t2, ω_n) its slip and twist: −W⁻¹ u are the impulses (t1, t2, twist)
    that stop them (the solve's update_anchor, the bounce's friction)."""
    u0, u1, u2 = pair_velocity(M, k, 0, p), pair_velocity(M, k, 1, p), pair_velocity(M, k, 2, p)
    o = W_INV
    return ((M[k, o] * u0 + M[k, o + 1] * u1 + M[k, o + 2] * u2),
            (M[k, o + 3] * u0 + M[k, o + 4] * u1 + M[k, o + 5] * u2),
            (M[k, o + 6] * u0 + M[k, o + 7] * u1 + M[k, o + 8] * u2))


@njit(cache=True, inline="always")
def update_anchor(R, M, k, first, count, sliding, p):
    """One update of manifold k's anchor (rows first..first + count − 1) on
    its pair's velocities p (pair_velocity.py: the anchor table shares the
    rows' column layout); sliding: its kinetic flag (MI's M_SLIDING). Returns
    (p after it, its largest impulse change)."""
    ln = 0.0
    for c in range(first, first + count):
        ln += R[c, LAM]
    s0, s1, s2 = anchor_stopping(M, k, p)
    old0, old1, old2 = M[k, M_LAM], M[k, M_LAM + 1], M[k, M_LAM + 2]
    n0, n1, n2 = old0 - s0, old1 - s1, old2 - s2
    n0, n1, n2 = anchor_cap(M, k, n0, n1, n2, ln, sliding)
    M[k, M_LAM], M[k, M_LAM + 1], M[k, M_LAM + 2] = n0, n1, n2
    p = pair_impulses(M, k, n0 - old0, n1 - old1, n2 - old2, p)
    return p, max(abs(n0 - old0), max(abs(n1 - old1), abs(n2 - old2)))


@njit(cache=True, inline="always")
def anchor_cap(M, k, n0, n1, n2, ln, sliding):
    """Coulomb's bound on the anchor's impulses: tangential within μ Σλ_n,
    the twist within μ Σλ_n r̄."""
    o = W_INV
    mu = M[k, M_MU_K] if sliding else M[k, M_MU_S]
    lim = mu * ln
    mag2 = n0 * n0 + n1 * n1
    if mag2 > lim * lim:
        if sliding:              # μ_k Σλ_n against the slip it is left with (kinetic_bound.py)
            n0, n1 = kinetic_bound(M[k, o], 0.5 * (M[k, o + 1] + M[k, o + 3]), M[k, o + 4], n0, n1,
                                   lim)
        else:                    # the static bound, in the direction that would hold
            s = lim / math.sqrt(mag2 + _TINY)
            n0, n1 = n0 * s, n1 * s
    twist = mu * ln * M[k, RADIUS]
    return n0, n1, min(max(n2, -twist), twist)


@njit(cache=True, inline="always")
def anchor_friction_out(R, M, MI, friction):
    """The anchors' tangential impulses shared equally by their rows, as world
    vectors (the warm cache and the events read the rows)."""
    for k in range(len(MI)):
        first, count = MI[k, FIRST], MI[k, COUNT]
        if count < 2:
            continue
        for c in range(first, first + count):
            for i in range(3):
                friction[c, i] = (M[k, M_LAM] * M[k, L + i]
                                  + M[k, M_LAM + 1] * M[k, L + STRIDE + i]) / count
