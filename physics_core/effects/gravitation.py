"""Newtonian attraction between every pair of bodies, F = G m_A m_B / r² u_AB (COURSE.md 2).

Softened (Plummer): F_i = Σ_j G m_i m_j d_ij / (|d_ij|² + ε²)^{3/2}, so
coincident bodies feel no infinite force (d = 0 gives exactly 0). Each
pair's term is computed from the same operands in both directions, so it is
equal and opposite to the last bit (Newton 3); only the row sums round.
Evaluated in row blocks to keep memory at O(block · n).
"""
import numpy as np

BLOCK = 512


def make(model):
    p = model.effects["gravitation"]
    idx = np.flatnonzero(model.mass > 0)
    m = model.mass[idx]
    eps2 = p.softening ** 2
    G = p.G

    def apply(kin, force, torque):
        x = kin.pos[idx]
        acc = np.empty_like(x)
        for s in range(0, len(idx), BLOCK):
            d = x[None, :, :] - x[s:s + BLOCK, None, :]
            r2 = np.einsum("ijk,ijk->ij", d, d) + eps2
            w = (G * (m[s:s + BLOCK, None] * m[None, :])) / (r2 * np.sqrt(r2))
            acc[s:s + BLOCK] = np.einsum("ij,ijk->ik", w, d)
        force[idx] += acc
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
