"""Friction on the bounce of a manifold of two or more points, at its anchor
(COURSE.md 5: friction on a collision impulse; manifold_friction.py).

The points of a manifold bounce together (collision_pass.py), and friction
acts on their total normal impulse Σλ_i at the manifold's anchor, the
centroid of its points, as in the solve: the impulse that stops the slip
and the twist there (W⁻¹ of the anchor's three rows), held while the
tangential part is within μ_s Σλ_i; past it, the body slides and takes
μ_k Σλ_i against the slip it is left with (kinetic_bound.py), the twist
within μ Σλ_i r̄ (manifold_friction.anchor_cap).

Applied point by point instead, each point's friction on the velocities
the one before left, it turned a body that slid along a face: a face's
keys go round it, so its first two corners in key order stand on one side,
and the first corner's impulse turned the body about the normal before
the next corners' slip was measured. Three cubes in a plane, the top one
landing at 2.3 m/s across the two below, left the pass moving out of
their plane at 4.78 mm/s and turning at 0.138 rad/s about the vertical
(1.46 mm/s and 0.027 rad/s with the corners taken diagonal first); a
pyramid of 10,000 boxes leaned out of its plane.

The anchor's impulse is shared by the points in proportion to their λ_i,
in each point's tangents, for the events (J, bounce.add_bounces); its twist
has no part there.
"""
from numba import njit

from .contact_layout import DIR, STRIDE
from .manifold_friction import L, M_MU_S, anchor_cap, anchor_stopping
from .pair_velocity import load_pair, pair_impulses, store_pair


@njit(cache=True, inline="always")
def _share(M, k, R, first, end, lam, n0, n1, ln, J):
    """J[c, 1:3] += the part λ_c / ln of the tangential impulse n0 t1 + n1 t2
    (the anchor's tangents) in row c's own tangents."""
    F0 = n0 * M[k, L] + n1 * M[k, L + STRIDE]
    F1 = n0 * M[k, L + 1] + n1 * M[k, L + STRIDE + 1]
    F2 = n0 * M[k, L + 2] + n1 * M[k, L + STRIDE + 2]
    for c in range(first, end):
        if not lam[c] > 0.0:
            continue
        w = lam[c] / ln
        for r in (1, 2):
            o = DIR + STRIDE * r
            f = 0.0
            f += F0 * R[c, o]
            f += F1 * R[c, o + 1]
            f += F2 * R[c, o + 2]
            J[c, r] += w * f


@njit(cache=True)
def anchor_bounce_friction(M, k, R, first, end, a, b, vel, omega, lam, J):
    """Friction on the bounce of manifold k (rows first..end − 1, bodies a
    and b, normal impulses lam[c]) at its anchor (module docstring),
    applied to vel and omega and shared into J."""
    ln = 0.0
    for c in range(first, end):
        if lam[c] > 0.0:
            ln += lam[c]
    if not ln > 0.0:
        return
    p = load_pair(vel, omega, a, b)
    s0, s1, s2 = anchor_stopping(M, k, p)
    n0, n1, n2 = -s0, -s1, -s2
    grip = M[k, M_MU_S] * ln
    n0, n1, n2 = anchor_cap(M, k, n0, n1, n2, ln, not n0 * n0 + n1 * n1 <= grip * grip)
    store_pair(vel, omega, a, b, pair_impulses(M, k, n0, n1, n2, p))
    _share(M, k, R, first, end, lam, n0, n1, ln, J)
