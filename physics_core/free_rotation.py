"""Torque-free rotation of rigid bodies over one (sub)step (COURSE.md 3 and 4).

With no torque the world angular momentum L is constant, but ω = I_w⁻¹ L
changes as an asymmetric body turns (its inertia tensor turns with it).
Advancing the orientation with the start-of-step ω, as explicit Euler does,
lets the rotational energy ½ L·ω creep up step after step (a tumbling box
gains ~5 % in 10 s at 240 Hz).

`advance` instead splits the free rotation into rotations about the body's
own principal axes (Dullweber, Leimkuhler & McLachlan, "Symplectic splitting
methods for rigid body molecular dynamics", J. Chem. Phys. 107, 1997):
x for h/2, y for h/2, z for h, y for h/2, x for h/2. Each part turns the
body about axis i by θ = τ L_i / I_i, which leaves L_i unchanged and so is
an exact flow; the symmetric composition is second order, keeps L exactly
(to round-off) and keeps the energy bounded instead of drifting.

A body with equal principal moments (sphere, cube) rotates about the fixed
L at ω = L / I; for those rows the exact exponential map is used instead,
and the splitting runs only on the other rows (RowSplit, computed once per
World): a scene of spheres never pays for it.

Everything is compiled one body at a time (`advance_one`, `split_one`,
`diagonal_one`, `turn_one`, on 4-tuple quaternions and 3-tuple vectors) so
that the integrators' loops over bodies call it directly; the array
functions (`advance`, `turn`, `world_momentum`, `world_velocity`) are loops
over those.
"""
import math

import numpy as np
from numba import njit

from .quaternion import integrate_one, normalize_one, rotate_inverse_one, rotate_one

_SEQUENCE = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))
_AXES = tuple(axis for axis, _ in _SEQUENCE)
_FRACTIONS = tuple(frac for _, frac in _SEQUENCE)


def isotropic_rows(inertia: np.ndarray) -> np.ndarray:
    """Bodies whose three principal moments are equal (to 1e-12 relative)."""
    return np.ptp(inertia, axis=1) <= 1e-12 * np.max(np.abs(inertia), axis=1)


class RowSplit:
    """The bodies of a scene split once into isotropic and other rows, so a
    step does no per-row test: with every body isotropic (a scene of spheres
    and cubes) the splitting below never runs. `mask` is the per-body flag
    the compiled loops read."""

    def __init__(self, isotropic):
        isotropic = np.asarray(isotropic, dtype=bool)
        self.n = len(isotropic)
        self.mask = np.ascontiguousarray(isotropic)
        self.iso = np.flatnonzero(isotropic)
        self.aniso = np.flatnonzero(~isotropic)
        self.all_iso = len(self.aniso) == 0
        self.no_iso = len(self.iso) == 0


def _rows(isotropic) -> RowSplit:
    return isotropic if isinstance(isotropic, RowSplit) else RowSplit(isotropic)


# ---- one body --------------------------------------------------------------------

@njit(cache=True, inline="always")
def diagonal_one(q, d, v, iso):
    """R diag(d) Rᵀ v for one body: the principal-axis diagonal `d` applied in
    world axes (L = I_w ω with d = I, ω = I_w⁻¹ L with d = I⁻¹). For an
    isotropic body I_w = I 1 in any pose (COURSE.md 3), so it is d v without
    turning v into the body frame and back."""
    if iso:
        return (d[0] * v[0], d[0] * v[1], d[0] * v[2])
    b = rotate_inverse_one(q, v)
    return rotate_one(q, (d[0] * b[0], d[1] * b[1], d[2] * b[2]))


@njit(cache=True, inline="always")
def turn_one(q, omega, h):
    """q advanced by the exact exponential map of ω h; with ω = 0 (a body at
    rest, or asleep) q is returned as it is."""
    if omega[0] != 0.0 or omega[1] != 0.0 or omega[2] != 0.0:
        return integrate_one(q, omega, h)
    return q


@njit(cache=True, inline="always")
def _turn_about(axis, c, s, q):
    """c q + s (q ⊗ e_i): the body turned about its own axis i. q ⊗ e_i is a
    signed permutation of q: (−x, w, z, −y), (−y, −z, w, x), (−z, y, −x, w)."""
    w, x, y, z = q
    if axis == 0:
        return (c * w - s * x, c * x + s * w, c * y + s * z, c * z - s * y)
    if axis == 1:
        return (c * w - s * y, c * x - s * z, c * y + s * w, c * z + s * x)
    return (c * w - s * z, c * x + s * y, c * y - s * x, c * z + s * w)


@njit(cache=True, inline="always")
def _kick_about(axis, c2m1, s2, L):
    """Body-frame L turned by −θ about axis i: L + (cos θ − 1) L_⊥ + sin θ (L × e_i),
    with (L × e_i)_j = L_k, (L × e_i)_k = −L_j for (i, j, k) cyclic; L_i is kept."""
    a, b, c = L
    if axis == 0:
        return (a, (b + c2m1 * b) + s2 * c, (c + c2m1 * c) - s2 * b)
    if axis == 1:
        return ((a + c2m1 * a) - s2 * c, b, (c + c2m1 * c) + s2 * a)
    return ((a + c2m1 * a) + s2 * b, (b + c2m1 * b) - s2 * a, c)


@njit(cache=True, inline="always")
def split_one(q, L, inv, h):
    """The symmetric splitting over principal axes for one body: (new q, new world ω)."""
    Lb = rotate_inverse_one(q, L)                          # body-frame L
    out = q
    for step in range(len(_AXES)):
        axis = _AXES[step]
        half = (0.5 * _FRACTIONS[step] * h) * Lb[axis] * inv[axis]
        c, s = math.cos(half), math.sin(half)
        # turn the body about its own axis by θ = 2·half ...
        out = _turn_about(axis, c, s, out)
        # ... so L seen from the body turns by −θ about that axis
        c2, s2 = 1.0 - 2.0 * s * s, 2.0 * s * c
        Lb = _kick_about(axis, c2 - 1.0, s2, Lb)
    out = normalize_one(out)
    return out, rotate_one(out, (inv[0] * Lb[0], inv[1] * Lb[1], inv[2] * Lb[2]))


@njit(cache=True, inline="always")
def advance_one(q, L, inv, h, iso):
    """(new orientation, new world ω) of one body after a torque-free rotation
    of length h; an isotropic body turns about the fixed L at ω = L / I by the
    exact map, any other by the splitting."""
    if iso:
        omega = (L[0] * inv[0], L[1] * inv[0], L[2] * inv[0])
        return turn_one(q, omega, h), omega
    return split_one(q, L, inv, h)


# ---- arrays of bodies ------------------------------------------------------------

@njit(cache=True)
def _diagonal_rows(q, diagonal, v, iso, out):
    for i in range(len(q)):
        d = (diagonal[i, 0], diagonal[i, 1], diagonal[i, 2])
        q_i = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        r = diagonal_one(q_i, d, (v[i, 0], v[i, 1], v[i, 2]), iso[i])
        out[i, 0], out[i, 1], out[i, 2] = r


@njit(cache=True)
def _turn_rows(q, omega, h, out):
    for i in range(len(q)):
        q_i = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = turn_one(q_i, (omega[i, 0], omega[i, 1], omega[i, 2]), h)


@njit(cache=True)
def _advance_rows(q, L, inv_inertia, h, iso, out_q, out_omega):
    for i in range(len(q)):
        q_i = (q[i, 0], q[i, 1], q[i, 2], q[i, 3])
        inv = (inv_inertia[i, 0], inv_inertia[i, 1], inv_inertia[i, 2])
        q_new, omega = advance_one(q_i, (L[i, 0], L[i, 1], L[i, 2]), inv, h, iso[i])
        out_q[i, 0], out_q[i, 1], out_q[i, 2], out_q[i, 3] = q_new
        out_omega[i, 0], out_omega[i, 1], out_omega[i, 2] = omega


def world_momentum(q, inertia, omega, isotropic):
    """L = I_w ω. For an isotropic body I_w = I 1 in any pose (COURSE.md 3),
    so L = I ω without turning ω into the body frame and back."""
    out = np.empty(np.shape(omega))
    _diagonal_rows(q, inertia, omega, _rows(isotropic).mask, out)
    return out


def world_velocity(q, inv_inertia, L, isotropic):
    """ω = I_w⁻¹ L (the inverse of world_momentum)."""
    out = np.empty(np.shape(L))
    _diagonal_rows(q, inv_inertia, L, _rows(isotropic).mask, out)
    return out


def turn(q, omega, h):
    """q advanced by the exact exponential map of ω h; rows with ω = 0 are
    left as they are (a body at rest, or asleep, costs nothing)."""
    out = np.empty(np.shape(q))
    _turn_rows(q, omega, float(h), out)
    return out


def advance(q, L, inv_inertia, h, isotropic):
    """(new orientation, new world ω) after a torque-free rotation of length h.

    q: (n, 4) orientations; L: (n, 3) world angular momentum, kept constant;
    inv_inertia: (n, 3) principal inverse moments (0 for frozen bodies);
    isotropic: (n,) bool or a RowSplit; those rows rotate about the fixed L at
    ω = L / I, advanced by the exact map, and only the others are split."""
    out_q, out_omega = np.empty(np.shape(q)), np.empty(np.shape(L))
    _advance_rows(q, L, inv_inertia, float(h), _rows(isotropic).mask, out_q, out_omega)
    return out_q, out_omega


def _split(q, L, inv_inertia, h):
    """The symmetric splitting over principal axes, for every row given."""
    return advance(q, L, inv_inertia, h, np.zeros(len(q), dtype=bool))
