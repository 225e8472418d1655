"""The kinetic friction impulse of one solver update (COURSE.md 2 and 5).

A sliding contact takes μ_k F_N against its sliding. The solver updates a
contact's friction impulse λ (2 tangents) many times a substep, and "its
sliding" must be the slip it is left with, or the update does not settle:
taken along the slip before the update (which already carries the old
impulse), the direction flips every update whenever the free slip is
between one and two times what μ_k λ_n can take off (a sphere's friction
traded between two directions 100° apart, its spin between −1.5 and
3.5 rad/s, sweep after sweep, in a forming pile).

`kinetic_bound` returns the impulse on |λ| = lim whose slip after the
update is against it. With A = W_tt⁻¹ (the tangent block's inverse) and λ*
the impulse that would stop the slip, the slip left is W (λ − λ*); for
λ = (I + σ A)⁻¹ λ* that is −σ λ, against λ for every σ ≥ 0, and σ is the
one with |λ| = lim: the point of the friction disk that dissipates most.
It is found by Newton's method on 1/|λ(σ)| − 1/lim, which is nearly linear
in σ (Moré and Sorensen's trust-region step), started from the answer for
A's largest eigenvalue alone (_first_sigma): for an isotropic A it is
exact there (one evaluation, against two from σ = 0), and an anisotropic
one takes one Newton step fewer (2-6 evaluations, against 3-7, on random
tangent blocks).
"""
import math

from numba import njit

_TINY = 1e-300
NEWTON_STEPS = 30          # a few suffice; the cap keeps a bad case finite
# |λ*| / lim above this: σ ~ |λ*| / lim, and (I + σ A)'s determinant (~σ²)
# would overflow; λ is then taken at its limit for σ → ∞, along A⁻¹ λ*
# (a friction coefficient of 1e-309 made the solve NaN)
FAR = 1e60


@njit(cache=True)
def _shrunk(a11, a12, a22, lt1, lt2, sigma):
    """(I + σ A)⁻¹ λ* and its derivative in σ, −(I + σ A)⁻¹ A λ (A symmetric 2×2)."""
    m11, m12, m22 = 1.0 + sigma * a11, sigma * a12, 1.0 + sigma * a22
    inv = 1.0 / (m11 * m22 - m12 * m12)
    x1, x2 = (m22 * lt1 - m12 * lt2) * inv, (m11 * lt2 - m12 * lt1) * inv
    y1, y2 = a11 * x1 + a12 * x2, a12 * x1 + a22 * x2
    return x1, x2, -(m22 * y1 - m12 * y2) * inv, -(m11 * y2 - m12 * y1) * inv


@njit(cache=True)
def _first_sigma(a11, a12, a22, norm, lim):
    """Where Newton starts: the σ that would be the answer if A were its
    largest eigenvalue a times the identity, (|λ*|/lim − 1)/a. |(I + σA)⁻¹ λ*|
    ≥ |λ*|/(1 + σ a) there, so it lies at or below the answer, on the side
    Newton converges from as it does from σ = 0; for an isotropic A (a
    sphere's contact) it is the answer, and one evaluation confirms it."""
    mid = 0.5 * (a11 + a22)
    top = mid + math.sqrt(0.25 * (a11 - a22) ** 2 + a12 * a12)
    if not (top > 0.0 and norm > lim):
        return 0.0
    return (norm / lim - 1.0) / top


@njit(cache=True)
def _far_limit(a11, a12, a22, lt1, lt2, lim):
    """λ on |λ| = lim along A⁻¹ λ* (the direction of (I + σ A)⁻¹ λ* as σ → ∞;
    A's adjugate, as A is positive definite); 0 when that is not defined."""
    y1, y2 = a22 * lt1 - a12 * lt2, a11 * lt2 - a12 * lt1
    size = math.sqrt(y1 * y1 + y2 * y2)
    if not (size > 0.0 and size < math.inf):
        return 0.0, 0.0
    return y1 * (lim / size), y2 * (lim / size)


@njit(cache=True)
def kinetic_bound(a11, a12, a22, lt1, lt2, lim):
    """λ on |λ| = lim with the slip after the update against it (module
    docstring); A = [[a11, a12], [a12, a22]] = W_tt⁻¹, λ* = (lt1, lt2) the
    impulse that would stop the slip."""
    if not lim > 0.0:
        return 0.0, 0.0
    norm = math.sqrt(lt1 * lt1 + lt2 * lt2)
    if norm > FAR * lim:
        return _far_limit(a11, a12, a22, lt1, lt2, lim)
    sigma = _first_sigma(a11, a12, a22, norm, lim)
    x1, x2 = lt1, lt2
    for _ in range(NEWTON_STEPS):
        x1, x2, d1, d2 = _shrunk(a11, a12, a22, lt1, lt2, sigma)
        norm = math.sqrt(x1 * x1 + x2 * x2)
        slope = -(x1 * d1 + x2 * d2) / (norm * norm * norm)     # d(1/|λ|)/dσ ≥ 0
        if abs(norm - lim) <= 1e-14 * lim or not slope > 0.0:
            break
        sigma = max(sigma - (1.0 / norm - 1.0 / lim) / slope, 0.0)
    scale = lim / math.sqrt(x1 * x1 + x2 * x2 + _TINY)
    return x1 * scale, x2 * scale
