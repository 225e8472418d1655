"""Newtonian attraction between every pair of bodies, F = G m_A m_B / r² u_AB (COURSE.md 2).

Softened (Plummer): F_i = Σ_j G m_i m_j d_ij / (|d_ij|² + ε²)^{3/2}, so
coincident bodies feel no infinite force (d = 0 gives exactly 0). Each
pair's term is computed once, from the same operands, and added to one body
and subtracted from the other, so it is equal and opposite to the last bit
(Newton 3); only the sums per body round. Each body's sum runs over the
others in index order. A compiled O(n²) loop over pairs, with O(n) memory:
the per-body sums are kept in a scratch array made once with the constants
(`constants`), so an evaluation allocates nothing.
"""
import math

import numpy as np
from numba import njit

BLOCK = 512     # rows per block of the (numpy) potential


@njit(cache=True)
def pair_forces(pos, idx, m, G, eps2, force, acc):
    """force[idx] += Σ_j G m_i m_j d_ij / (|d_ij|² + ε²)^{3/2}, d_ij = x_j − x_i;
    acc: scratch, at least len(idx) rows, overwritten."""
    n = len(idx)
    for a in range(n):
        for k in range(3):
            acc[a, k] = 0.0
    for a in range(n):
        i = idx[a]
        for b in range(a + 1, n):
            j = idx[b]
            dx, dy, dz = pos[j, 0] - pos[i, 0], pos[j, 1] - pos[i, 1], pos[j, 2] - pos[i, 2]
            r2 = dx * dx + dy * dy + dz * dz + eps2
            w = (G * (m[a] * m[b])) / (r2 * math.sqrt(r2))
            acc[a, 0] += w * dx
            acc[a, 1] += w * dy
            acc[a, 2] += w * dz
            acc[b, 0] -= w * dx
            acc[b, 1] -= w * dy
            acc[b, 2] -= w * dz
    for a in range(n):
        for k in range(3):
            force[idx[a], k] += acc[a, k]


def constants(model):
    """(idx, m, G, ε², acc): the bodies with mass, their masses (kg), G, the
    squared softening length (m²) and the scratch sums (len(idx), 3)."""
    p = model.effects["gravitation"]
    idx = np.flatnonzero(model.mass > 0).astype(np.int64)
    m = np.array(model.mass[idx], dtype=float)
    return idx, m, float(p.G), float(p.softening ** 2), np.zeros((len(idx), 3))


def unused():
    """The types of `constants` with no bodies, for a scene without gravitation."""
    return np.zeros(0, dtype=np.int64), np.zeros(0), 0.0, 0.0, np.zeros((0, 3))


@njit(cache=True)
def add(c, pos, quat, vel, omega, force, torque):
    """The effect's kernel on the common signature of effects/ (no torque)."""
    idx, m, G, eps2, acc = c
    pair_forces(pos, idx, m, G, eps2, force, acc)


def make(model):
    """apply(kin, force, torque): `add` with this model's constants (World.forces' path)."""
    c = constants(model)

    def apply(kin, force, torque):
        add(c, kin.pos, kin.quat, kin.vel, kin.omega, force, torque)
    return apply


def potential(model, state) -> float:
    """U = -Σ_{i<j} G m_i m_j / sqrt(r² + ε²), the potential of the softened force."""
    p = model.effects["gravitation"]
    idx = np.flatnonzero(model.mass > 0)
    x, m = state.pos[idx], model.mass[idx]
    cols = np.arange(len(idx))[None, :]
    total = 0.0
    for s in range(0, len(idx), BLOCK):
        d = x[None, :, :] - x[s:s + BLOCK, None, :]
        r = np.sqrt(np.einsum("ijk,ijk->ij", d, d) + p.softening ** 2)
        rows = np.arange(s, s + len(r))[:, None]
        u = p.G * m[s:s + BLOCK, None] * m[None, :] / r
        total -= float(np.sum(np.where(cols > rows, u, 0.0)))   # each pair once
    return total
