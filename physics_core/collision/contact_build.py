"""Contact rows of one substep, compiled: frame, lever arms, effective masses,
friction coefficients, restitution and the speculative bias (COURSE.md 5).

`build_rows` fills one row of R and I (contact_layout.py) per contact of
the detected manifold. Its helpers are inlined (lever_arms, coupling):
called, they made it 11 % slower on a dense pile of 1,000 spheres
(1,424 contacts, 275 -> 308 µs). Static and sleeping bodies have zero inverse mass
and inertia (infinite mass, COURSE.md 5), so they take no velocity change.

Speculative contact: the integrator moved every body with its unconstrained
velocity u0, and the pair was detected at the end pose with separation
s_end = −depth. It started the substep at s0 = s_end − h u0_n, so the
normal row asks for u_n ≥ −max(s0, 0)/h: close the gap, never cross it; an
overlap is removed by the position pass, never by adding velocity. A body
the ccd stage moved back to its time of impact already sits at the start
of its remaining motion, so there s0 = s_end.
"""
import math

from numba import njit

from ..quaternion import row4, to_matrix_one
from .contact_layout import (ARM_A, ARM_B, BIAS, BODY_A, BODY_B, DEPTH, DIR, E, G_TN, INV_MASS_A,
                             INV_MASS_B, K_A, K_B, LAM, MASS_N, MU, MU_K, MU_S, SLIDING, STRIDE,
                             TURN_A, TURN_B, U0, W_TT, W_TT_INV)
from .scratch import take_bools, take_rows

RESTITUTION_RULES = {"effective_mass": 0, "mean": 1, "min": 2, "max": 3}
_TINY = 1e-30


@njit(cache=True, inline="always")
def world_inverse_inertia(q, inv_inertia, out, row):
    """out[row] (9,) = I_w⁻¹ = R diag(I⁻¹) Rᵀ (COURSE.md 3), row-major."""
    R = to_matrix_one(q)
    for i in range(3):
        for j in range(3):
            out[row, 3 * i + j] = (R[i][0] * inv_inertia[0] * R[j][0]
                                   + R[i][1] * inv_inertia[1] * R[j][1]
                                   + R[i][2] * inv_inertia[2] * R[j][2])


@njit(cache=True, inline="always")
def inertia_table(a, b, quat, inv_inertia, store):
    """(n, 9) I_w⁻¹ of every body in a contact (a[c] or b[c]), each computed
    once however many contacts it has; the other rows are not set. In the
    substep's scratch (scratch.py)."""
    n = len(quat)
    table, done = take_rows(store, n, 9), take_bools(store, n)
    done[:] = False
    for side in (a, b):
        for c in range(len(side)):
            i = side[c]
            if not done[i]:
                world_inverse_inertia(row4(quat, i), inv_inertia[i], table, i)
                done[i] = True
    return table


@njit(cache=True, inline="always")
def tangent_frame(R, c, nx, ny, nz):
    """Rows n, t1, t2 of contact c: an orthonormal basis from n alone (Duff et
    al. 2017, branch-free, never NaN for a unit n; friction.py)."""
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    t1, t2 = DIR + STRIDE, DIR + 2 * STRIDE
    R[c, DIR], R[c, DIR + 1], R[c, DIR + 2] = nx, ny, nz
    R[c, t1], R[c, t1 + 1], R[c, t1 + 2] = 1.0 + sign * nx * nx * a, sign * b, -sign * nx
    R[c, t2], R[c, t2 + 1], R[c, t2 + 2] = b, sign + ny * ny * a, -ny


@njit(cache=True, inline="always")
def lever_arms(R, c, arm, turn, rx, ry, rz, iw, body, first, stop):
    """r × d_r and I_w⁻¹ (r × d_r) of one body (iw[body]: its I_w⁻¹, row-major),
    for the directions first..stop − 1."""
    for r in range(first, stop):
        dx, dy, dz = R[c, DIR + STRIDE * r], R[c, DIR + STRIDE * r + 1], R[c, DIR + STRIDE * r + 2]
        cx, cy, cz = ry * dz - rz * dy, rz * dx - rx * dz, rx * dy - ry * dx
        o = arm + STRIDE * r
        R[c, o], R[c, o + 1], R[c, o + 2] = cx, cy, cz
        o = turn + STRIDE * r
        R[c, o] = iw[body, 0] * cx + iw[body, 1] * cy + iw[body, 2] * cz
        R[c, o + 1] = iw[body, 3] * cx + iw[body, 4] * cy + iw[body, 5] * cz
        R[c, o + 2] = iw[body, 6] * cx + iw[body, 7] * cy + iw[body, 8] * cz


@njit(cache=True, inline="always")
def coupling(R, c, r, s):
    """W_rs = u_r's change per unit impulse along row s, summed over both bodies."""
    o, q = DIR + STRIDE * r, DIR + STRIDE * s
    dd = R[c, o] * R[c, q] + R[c, o + 1] * R[c, q + 1] + R[c, o + 2] * R[c, q + 2]
    wa = 0.0
    wb = 0.0
    for i in range(3):
        wa += R[c, ARM_A + STRIDE * r + i] * R[c, TURN_A + STRIDE * s + i]
        wb += R[c, ARM_B + STRIDE * r + i] * R[c, TURN_B + STRIDE * s + i]
    return (R[c, INV_MASS_A] * dd + wa) + (R[c, INV_MASS_B] * dd + wb)


@njit(cache=True, inline="always")
def normal_mass(R, c):
    """1/W_nn, the normal row's effective mass (COURSE.md 5's denominator)."""
    return 1.0 / max(coupling(R, c, 0, 0), _TINY)


@njit(cache=True, inline="always")
def normal_masses(R, c):
    """K_A, K_B (each body's part of W_00: restitution weights them) and 1/W_nn."""
    k_a = R[c, INV_MASS_A]
    k_b = R[c, INV_MASS_B]
    for i in range(3):
        k_a += R[c, ARM_A + i] * R[c, TURN_A + i]
        k_b += R[c, ARM_B + i] * R[c, TURN_B + i]
    R[c, K_A], R[c, K_B] = k_a, k_b
    R[c, MASS_N] = normal_mass(R, c)


@njit(cache=True, inline="always")
def tangent_block(R, c):
    """The tangent block W_tt, its inverse and W_tt⁻¹ W_tn: what a single
    point's friction reads (sequential_impulses.update_contact, and a
    single point's bounce friction, bounce.bounce_friction)."""
    w11, w12 = coupling(R, c, 1, 1), coupling(R, c, 1, 2)
    w21, w22 = coupling(R, c, 2, 1), coupling(R, c, 2, 2)
    det = w11 * w22 - w12 * w21
    inv_det = 1.0 / (det if abs(det) > _TINY else _TINY)
    R[c, W_TT], R[c, W_TT + 1], R[c, W_TT + 2], R[c, W_TT + 3] = w11, w12, w21, w22
    i11, i12, i21, i22 = w22 * inv_det, -w12 * inv_det, -w21 * inv_det, w11 * inv_det
    R[c, W_TT_INV], R[c, W_TT_INV + 1], R[c, W_TT_INV + 2], R[c, W_TT_INV + 3] = i11, i12, i21, i22
    t1n, t2n = coupling(R, c, 1, 0), coupling(R, c, 2, 0)
    R[c, G_TN], R[c, G_TN + 1] = i11 * t1n + i12 * t2n, i21 * t1n + i22 * t2n


@njit(cache=True, inline="always")
def effective_masses(R, c):
    """1/W_nn, the tangent block and its inverse, and W_tt⁻¹ W_tn."""
    normal_masses(R, c)
    tangent_block(R, c)


@njit(cache=True, inline="always")
def _no_tangent_block(R, c):
    """NaN in the tangent block's columns of a row whose friction is its
    manifold's anchor (manifold_friction.py): no solve reads them, and a
    reader that did would make the step's finite check fail."""
    for j in range(W_TT, G_TN + 2):
        R[c, j] = math.nan


@njit(cache=True, inline="always")
def in_manifold(a, b, c):
    """Whether contact c shares its body pair with a neighbour: a manifold of
    two or more points (the contacts of one pair are consecutive)."""
    before = c > 0 and a[c - 1] == a[c] and b[c - 1] == b[c]
    after = c + 1 < len(a) and a[c + 1] == a[c] and b[c + 1] == b[c]
    return before or after


@njit(cache=True, inline="always")
def tangent_world(R, c, l1, l2, i):
    """Component i of l1 t1 + l2 t2, contact c's tangential impulses l1, l2
    as a world vector."""
    return l1 * R[c, DIR + STRIDE + i] + l2 * R[c, DIR + 2 * STRIDE + i]


@njit(cache=True, inline="always")
def row_velocity(R, c, r, a, b, vel, omega):
    """u_r = d_r·(v_b − v_a) + (r_b × d_r)·ω_b − (r_a × d_r)·ω_a."""
    o = STRIDE * r
    u = 0.0
    for i in range(3):
        u += (R[c, DIR + o + i] * (vel[b, i] - vel[a, i])
              + R[c, ARM_B + o + i] * omega[b, i] - R[c, ARM_A + o + i] * omega[a, i])
    return u


@njit(cache=True)
def pair_restitution(k_a, k_b, e_a, e_b, rule):
    """One C_R for the pair (restitution.py): a static or sleeping side is the
    rigid object the other's C_R is defined against; otherwise `rule`."""
    if k_a <= 0.0:
        return e_b
    if k_b <= 0.0:
        return e_a
    if rule == 1:
        return 0.5 * (e_a + e_b)
    if rule == 2:
        return min(e_a, e_b)
    if rule == 3:
        return max(e_a, e_b)
    return (k_a * e_a + k_b * e_b) / (k_a + k_b)


@njit(cache=True)
def start_separation(depth, u0_n, rewound, h):
    """s0, the pair's separation at the start of the substep (module docstring)."""
    return -depth if rewound else -depth - h * u0_n


@njit(cache=True)
def touch_shift(depth, s0):
    """How far each side's touching point lies from the midway point, along n
    (contact_arms): half the overlap the substep's own motion made."""
    return 0.5 * (depth - max(-s0, 0.0))


@njit(cache=True, inline="always")
def contact_arms(R, c, i, j, point, depth, pos, vel, omega, iw, h, rewound):
    """Lever arms of contact c (its frame already set) from each centre;
    returns s0, the pair's separation at the start of the substep (module
    docstring). The normal row's arms reach point[c].

    The friction rows' arms reach where the surfaces touched (COURSE.md 5:
    the offsets run from each centre to the point where the bodies touch).
    point[c] lies midway between surfaces that this substep's own motion
    pushed s_in = depth − max(−s0, 0) into each other (all of depth if they
    met during the substep, the overlap added since its start if they
    overlapped already), so each body's touching point is s = s_in / 2 from
    it: along +n on a, −n on b. A shift along n leaves r × n as it was: the
    normal rows do not change. On the midway point a ball resting on the
    floor rolled on a lever g h² / 2 short of its radius (one substep's sag
    under gravity) and ended 0.049 % under 5/7 v0. Between two moving
    bodies the two points are 2s apart along n, so friction there turns
    the pair by 2s λ_t; bodies resting on each other sag together (s = 0),
    so only a frictional impact between two moving bodies does, by the
    depth it made within its substep."""
    px, py, pz = point[c, 0], point[c, 1], point[c, 2]
    rax, ray, raz = px - pos[i, 0], py - pos[i, 1], pz - pos[i, 2]
    rbx, rby, rbz = px - pos[j, 0], py - pos[j, 1], pz - pos[j, 2]
    lever_arms(R, c, ARM_A, TURN_A, rax, ray, raz, iw, i, 0, 1)
    lever_arms(R, c, ARM_B, TURN_B, rbx, rby, rbz, iw, j, 0, 1)
    s0 = start_separation(depth, row_velocity(R, c, 0, i, j, vel, omega), rewound, h)
    s = touch_shift(depth, s0)
    sx, sy, sz = s * R[c, DIR], s * R[c, DIR + 1], s * R[c, DIR + 2]
    lever_arms(R, c, ARM_A, TURN_A, rax + sx, ray + sy, raz + sz, iw, i, 1, 3)
    lever_arms(R, c, ARM_B, TURN_B, rbx - sx, rby - sy, rbz - sz, iw, j, 1, 3)
    return s0


@njit(cache=True, inline="always")
def build_rows(R, I, a, b, point, normal, depth, pos, iw, vel, omega, inv_mass, material,
               mu_static, mu_kinetic, restitution, rule, h, toi):
    """Fill R, I for the k contacts (a, b, point, normal, depth); iw: the
    bodies' I_w⁻¹ (inertia_table)."""
    for c in range(len(a)):
        i, j = a[c], b[c]
        I[c, BODY_A], I[c, BODY_B], I[c, SLIDING] = i, j, 0
        tangent_frame(R, c, normal[c, 0], normal[c, 1], normal[c, 2])
        R[c, INV_MASS_A], R[c, INV_MASS_B] = inv_mass[i], inv_mass[j]
        s0 = contact_arms(R, c, i, j, point, depth[c], pos, vel, omega, iw, h,
                          toi[i] >= 0.0 or toi[j] >= 0.0)
        normal_masses(R, c)
        if in_manifold(a, b, c):
            _no_tangent_block(R, c)      # the anchor's friction (a bounce computes it)
        else:
            tangent_block(R, c)
        for r in range(3):
            R[c, U0 + r] = row_velocity(R, c, r, i, j, vel, omega)
            R[c, LAM + r] = 0.0
        R[c, MU_S] = mu_static[material[i], material[j]]
        R[c, MU_K] = mu_kinetic[material[i], material[j]]
        R[c, MU] = R[c, MU_S]
        R[c, E] = pair_restitution(R[c, K_A], R[c, K_B], restitution[i], restitution[j], rule)
        R[c, DEPTH] = depth[c]
        R[c, BIAS] = -max(s0, 0.0) / h
