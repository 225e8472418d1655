"""The velocities of a manifold's two bodies held as one value while its rows
are updated (COURSE.md 5: v± = v∓ ± j n / m, ω± = ω∓ ± I⁻¹ (r × j n)).

A manifold's rows all act on the same two bodies, one after the other
(sequential impulses), and each row reads the velocities the one before it
left. Read from and written back to the body arrays at every row, those
velocities go through memory between every two rows, and the compiler
cannot keep them in registers (the rows and the velocities are arrays it
must assume may overlap). Here they are loaded once per manifold update,
as a tuple of 12 floats (v_a, ω_a, v_b, ω_b), carried through its rows and
stored once: the same operations in the same order, so the same bits.

A row update that changes its three impulses at once applies them as one
(`pair_impulses`): the pair moves by the sum of the three rows' changes,
v_a −= (Σ_r dλ_r d_r) / m_a, ω_a −= Σ_r dλ_r I_wa⁻¹ (r_a × d_r), and the
same for b. Three impulses applied one after the other give the same
velocities but chain every component through three multiply–subtract steps,
one row waiting for the last; the sum takes the three rows' products side
by side (a dense pile of 1,000 spheres, 1,424 contacts, its sweep called on
its own: 148 → 103 µs, the same sweep loop with the one change).

`T` is a table with the contact rows' column layout (contact_layout.py:
direction, lever arms and their I_w⁻¹ images, inverse masses), which the
manifold anchors' table (manifold_friction.py) shares.
"""
from numba import njit

from .contact_layout import ARM_A, ARM_B, DIR, INV_MASS_A, INV_MASS_B, STRIDE, TURN_A, TURN_B


@njit(cache=True, inline="always")
def load_pair(vel, omega, a, b):
    """(v_a, ω_a, v_b, ω_b) of bodies a and b, 12 floats."""
    return (vel[a, 0], vel[a, 1], vel[a, 2], omega[a, 0], omega[a, 1], omega[a, 2],
            vel[b, 0], vel[b, 1], vel[b, 2], omega[b, 0], omega[b, 1], omega[b, 2])


@njit(cache=True, inline="always")
def store_pair(vel, omega, a, b, p):
    vel[a, 0], vel[a, 1], vel[a, 2] = p[0], p[1], p[2]
    omega[a, 0], omega[a, 1], omega[a, 2] = p[3], p[4], p[5]
    vel[b, 0], vel[b, 1], vel[b, 2] = p[6], p[7], p[8]
    omega[b, 0], omega[b, 1], omega[b, 2] = p[9], p[10], p[11]


@njit(cache=True, inline="always")
def pair_velocity(T, k, r, p):
    """u_r = d_r·(v_b − v_a) + (r_b × d_r)·ω_b − (r_a × d_r)·ω_a of row r of
    entry k (contact_build.row_velocity on the pair)."""
    o = STRIDE * r
    u = 0.0
    u += T[k, DIR + o] * (p[6] - p[0]) + T[k, ARM_B + o] * p[9] - T[k, ARM_A + o] * p[3]
    u += (T[k, DIR + o + 1] * (p[7] - p[1]) + T[k, ARM_B + o + 1] * p[10]
          - T[k, ARM_A + o + 1] * p[4])
    u += (T[k, DIR + o + 2] * (p[8] - p[2]) + T[k, ARM_B + o + 2] * p[11]
          - T[k, ARM_A + o + 2] * p[5])
    return u


@njit(cache=True, inline="always")
def pair_impulse(T, k, r, lam, p):
    """The pair after an impulse lam along row r of entry k
    (sequential_impulses.apply_impulse on the pair)."""
    o = STRIDE * r
    ima, imb = T[k, INV_MASS_A] * lam, T[k, INV_MASS_B] * lam
    d0, d1, d2 = T[k, DIR + o], T[k, DIR + o + 1], T[k, DIR + o + 2]
    return (p[0] - ima * d0, p[1] - ima * d1, p[2] - ima * d2,
            p[3] - lam * T[k, TURN_A + o], p[4] - lam * T[k, TURN_A + o + 1],
            p[5] - lam * T[k, TURN_A + o + 2],
            p[6] + imb * d0, p[7] + imb * d1, p[8] + imb * d2,
            p[9] + lam * T[k, TURN_B + o], p[10] + lam * T[k, TURN_B + o + 1],
            p[11] + lam * T[k, TURN_B + o + 2])


@njit(cache=True, inline="always")
def pair_impulses(T, k, l0, l1, l2, p):
    """The pair after impulses l0, l1, l2 along rows 0, 1, 2 of entry k at
    once (module docstring): their sum P = Σ λ_r d_r and turns
    Σ λ_r I_w⁻¹ (r × d_r). Written out: a helper returning each sum as a
    tuple, inlined, made a sweep 8 % slower."""
    ima, imb = T[k, INV_MASS_A], T[k, INV_MASS_B]
    P0 = l0 * T[k, DIR] + l1 * T[k, DIR + STRIDE] + l2 * T[k, DIR + 2 * STRIDE]
    P1 = l0 * T[k, DIR + 1] + l1 * T[k, DIR + STRIDE + 1] + l2 * T[k, DIR + 2 * STRIDE + 1]
    P2 = l0 * T[k, DIR + 2] + l1 * T[k, DIR + STRIDE + 2] + l2 * T[k, DIR + 2 * STRIDE + 2]
    A0 = l0 * T[k, TURN_A] + l1 * T[k, TURN_A + STRIDE] + l2 * T[k, TURN_A + 2 * STRIDE]
    A1 = l0 * T[k, TURN_A + 1] + l1 * T[k, TURN_A + STRIDE + 1] + l2 * T[k, TURN_A + 2 * STRIDE + 1]
    A2 = l0 * T[k, TURN_A + 2] + l1 * T[k, TURN_A + STRIDE + 2] + l2 * T[k, TURN_A + 2 * STRIDE + 2]
    B0 = l0 * T[k, TURN_B] + l1 * T[k, TURN_B + STRIDE] + l2 * T[k, TURN_B + 2 * STRIDE]
    B1 = l0 * T[k, TURN_B + 1] + l1 * T[k, TURN_B + STRIDE + 1] + l2 * T[k, TURN_B + 2 * STRIDE + 1]
    B2 = l0 * T[k, TURN_B + 2] + l1 * T[k, TURN_B + STRIDE + 2] + l2 * T[k, TURN_B + 2 * STRIDE + 2]
    return (p[0] - ima * P0, p[1] - ima * P1, p[2] - ima * P2, p[3] - A0, p[4] - A1, p[5] - A2,
            p[6] + imb * P0, p[7] + imb * P1, p[8] + imb * P2, p[9] + B0, p[10] + B1, p[11] + B2)
