"""Contact rows of one substep, compiled: frame, lever arms, effective masses,
friction coefficients, restitution and the speculative bias (COURSE.md 5).

`build_rows` fills one row of R and I (contact_layout.py) per contact of
the detected manifold. Static and sleeping bodies have zero inverse mass
and inertia (infinite mass, COURSE.md 5), so they take no velocity change.

Speculative contact: the integrator moved every body with its unconstrained
velocity u0, and the pair was detected at the end pose with separation
s_end = −depth. It started the substep at s0 = s_end − h u0_n, so the
normal row asks for u_n ≥ −max(s0, 0)/h: close the gap, never cross it; an
overlap is removed by the position pass, never by adding velocity. A body
the ccd stage moved back to its time of impact already sits at the start
of its remaining motion, so there s0 = s_end.
"""
import numpy as np
from numba import njit

from ..quaternion import row4, to_matrix_one
from .contact_layout import (ARM_A, ARM_B, BIAS, BODY_A, BODY_B, DEPTH, DIR, E, G_TN, INV_MASS_A,
                             INV_MASS_B, K_A, K_B, LAM, MASS_N, MU, MU_K, MU_S, SLIDING, TURN_A,
                             TURN_B, U0, W_TN, W_TT, W_TT_INV)

RESTITUTION_RULES = {"effective_mass": 0, "mean": 1, "min": 2, "max": 3}
_TINY = 1e-30


@njit(cache=True)
def world_inverse_inertia(q, inv_inertia, out):
    """out (3, 3) = I_w⁻¹ = R diag(I⁻¹) Rᵀ (COURSE.md 3)."""
    R = to_matrix_one(q)
    for i in range(3):
        for j in range(3):
            out[i, j] = (R[i][0] * inv_inertia[0] * R[j][0] + R[i][1] * inv_inertia[1] * R[j][1]
                         + R[i][2] * inv_inertia[2] * R[j][2])


@njit(cache=True)
def tangent_frame(R, c, nx, ny, nz):
    """Rows n, t1, t2 of contact c: an orthonormal basis from n alone (Duff et
    al. 2017, branch-free, never NaN for a unit n; friction.py)."""
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    R[c, DIR + 0], R[c, DIR + 1], R[c, DIR + 2] = nx, ny, nz
    R[c, DIR + 3], R[c, DIR + 4], R[c, DIR + 5] = 1.0 + sign * nx * nx * a, sign * b, -sign * nx
    R[c, DIR + 6], R[c, DIR + 7], R[c, DIR + 8] = b, sign + ny * ny * a, -ny


@njit(cache=True)
def lever_arms(R, c, arm, turn, rx, ry, rz, iw):
    """r × d_r and I_w⁻¹ (r × d_r) of one body, for the three directions."""
    for r in range(3):
        dx, dy, dz = R[c, DIR + 3 * r], R[c, DIR + 3 * r + 1], R[c, DIR + 3 * r + 2]
        cx, cy, cz = ry * dz - rz * dy, rz * dx - rx * dz, rx * dy - ry * dx
        o = arm + 3 * r
        R[c, o], R[c, o + 1], R[c, o + 2] = cx, cy, cz
        o = turn + 3 * r
        R[c, o] = iw[0, 0] * cx + iw[0, 1] * cy + iw[0, 2] * cz
        R[c, o + 1] = iw[1, 0] * cx + iw[1, 1] * cy + iw[1, 2] * cz
        R[c, o + 2] = iw[2, 0] * cx + iw[2, 1] * cy + iw[2, 2] * cz


@njit(cache=True)
def coupling(R, c, r, s):
    """W_rs = u_r's change per unit impulse along row s, summed over both bodies."""
    dd = (R[c, DIR + 3 * r] * R[c, DIR + 3 * s] + R[c, DIR + 3 * r + 1] * R[c, DIR + 3 * s + 1]
          + R[c, DIR + 3 * r + 2] * R[c, DIR + 3 * s + 2])
    wa = 0.0
    wb = 0.0
    for i in range(3):
        wa += R[c, ARM_A + 3 * r + i] * R[c, TURN_A + 3 * s + i]
        wb += R[c, ARM_B + 3 * r + i] * R[c, TURN_B + 3 * s + i]
    return (R[c, INV_MASS_A] * dd + wa) + (R[c, INV_MASS_B] * dd + wb)


@njit(cache=True)
def effective_masses(R, c):
    """1/W_nn, the tangent block and its inverse, W_tn and W_tt⁻¹ W_tn."""
    k_a = R[c, INV_MASS_A]
    k_b = R[c, INV_MASS_B]
    for i in range(3):
        k_a += R[c, ARM_A + i] * R[c, TURN_A + i]
        k_b += R[c, ARM_B + i] * R[c, TURN_B + i]
    R[c, K_A], R[c, K_B] = k_a, k_b
    R[c, MASS_N] = 1.0 / max(coupling(R, c, 0, 0), _TINY)
    w11, w12 = coupling(R, c, 1, 1), coupling(R, c, 1, 2)
    w21, w22 = coupling(R, c, 2, 1), coupling(R, c, 2, 2)
    det = w11 * w22 - w12 * w21
    inv_det = 1.0 / (det if abs(det) > _TINY else _TINY)
    R[c, W_TT], R[c, W_TT + 1], R[c, W_TT + 2], R[c, W_TT + 3] = w11, w12, w21, w22
    i11, i12, i21, i22 = w22 * inv_det, -w12 * inv_det, -w21 * inv_det, w11 * inv_det
    R[c, W_TT_INV], R[c, W_TT_INV + 1], R[c, W_TT_INV + 2], R[c, W_TT_INV + 3] = i11, i12, i21, i22
    t1n, t2n = coupling(R, c, 1, 0), coupling(R, c, 2, 0)
    R[c, W_TN], R[c, W_TN + 1] = t1n, t2n
    R[c, G_TN], R[c, G_TN + 1] = i11 * t1n + i12 * t2n, i21 * t1n + i22 * t2n


@njit(cache=True)
def row_velocity(R, c, r, a, b, vel, omega):
    """u_r = d_r·(v_b − v_a) + (r_b × d_r)·ω_b − (r_a × d_r)·ω_a."""
    u = 0.0
    for i in range(3):
        u += (R[c, DIR + 3 * r + i] * (vel[b, i] - vel[a, i])
              + R[c, ARM_B + 3 * r + i] * omega[b, i] - R[c, ARM_A + 3 * r + i] * omega[a, i])
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
def build_rows(R, I, a, b, point, normal, depth, pos, quat, vel, omega, inv_mass, inv_inertia,
               material, mu_static, mu_kinetic, restitution, rule, h, toi):
    """Fill R, I for the k contacts (a, b, point, normal, depth)."""
    iw = np.empty((3, 3))
    for c in range(len(a)):
        i, j = a[c], b[c]
        I[c, BODY_A], I[c, BODY_B], I[c, SLIDING] = i, j, 0
        tangent_frame(R, c, normal[c, 0], normal[c, 1], normal[c, 2])
        R[c, INV_MASS_A], R[c, INV_MASS_B] = inv_mass[i], inv_mass[j]
        world_inverse_inertia(row4(quat, i), inv_inertia[i], iw)
        lever_arms(R, c, ARM_A, TURN_A, point[c, 0] - pos[i, 0], point[c, 1] - pos[i, 1],
                   point[c, 2] - pos[i, 2], iw)
        world_inverse_inertia(row4(quat, j), inv_inertia[j], iw)
        lever_arms(R, c, ARM_B, TURN_B, point[c, 0] - pos[j, 0], point[c, 1] - pos[j, 1],
                   point[c, 2] - pos[j, 2], iw)
        effective_masses(R, c)
        for r in range(3):
            R[c, U0 + r] = row_velocity(R, c, r, i, j, vel, omega)
            R[c, LAM + r] = 0.0
        R[c, MU_S] = mu_static[material[i], material[j]]
        R[c, MU_K] = mu_kinetic[material[i], material[j]]
        R[c, MU] = R[c, MU_S]
        R[c, E] = pair_restitution(R[c, K_A], R[c, K_B], restitution[i], restitution[j], rule)
        R[c, DEPTH] = depth[c]
        s0 = -depth[c] if (toi[i] >= 0.0 or toi[j] >= 0.0) else -depth[c] - h * R[c, U0]
        R[c, BIAS] = -max(s0, 0.0) / h
