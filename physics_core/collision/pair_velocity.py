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

`T` is a table with the contact rows' column layout (contact_layout.py:
direction, lever arms and their I_w⁻¹ images, inverse masses), which the
manifold anchors' table (manifold_friction.py) shares.
"""
from numba import njit

from .contact_layout import ARM_A, ARM_B, DIR, INV_MASS_A, INV_MASS_B, TURN_A, TURN_B


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
    o = 3 * r
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
    o = 3 * r
    ima, imb = T[k, INV_MASS_A] * lam, T[k, INV_MASS_B] * lam
    d0, d1, d2 = T[k, DIR + o], T[k, DIR + o + 1], T[k, DIR + o + 2]
    return (p[0] - ima * d0, p[1] - ima * d1, p[2] - ima * d2,
            p[3] - lam * T[k, TURN_A + o], p[4] - lam * T[k, TURN_A + o + 1],
            p[5] - lam * T[k, TURN_A + o + 2],
            p[6] + imb * d0, p[7] + imb * d1, p[8] + imb * d2,
            p[9] + lam * T[k, TURN_B + o], p[10] + lam * T[k, TURN_B + o + 1],
            p[11] + lam * T[k, TURN_B + o + 2])
