"""Friction at contacts (COURSE.md 2 and 5): coefficients, tangent plane, static/kinetic cap.

Friction is two impulse rows in the tangent plane, solved together so the
tangential impulse is one vector. The course's tangent
`t = (n × (v_A − v_B)) × n` is undefined when the relative velocity is
parallel to n (a head-on hit); a fixed orthonormal basis (t1, t2) of the
plane, built from n alone, never is, and because both rows are solved as
one 2-D impulse the result does not depend on which basis is used: the
impulse comes out opposite the sliding velocity (the course's direction)
whenever there is sliding, and zero when there is none.
"""
import numpy as np

_TINY = 1e-30


def coefficients(model, a, b):
    """(μ_s, μ_k) per contact from the material pair table, either order (COURSE.md 2)."""
    ma, mb = model.material[a], model.material[b]
    return model.mu_static[ma, mb], model.mu_kinetic[ma, mb]


def tangent_basis(normal):
    """(t1, t2), each (k, 3): t1 ⟂ n from the world axis least aligned with n
    (x unless n is close to x, then y), t2 = n × t1. Deterministic, never NaN
    for a unit n."""
    helper = np.zeros_like(normal)
    use_y = np.abs(normal[:, 0]) > 0.57735
    helper[~use_y, 0] = 1.0
    helper[use_y, 1] = 1.0
    t1 = helper - normal * np.einsum("ij,ij->i", helper, normal)[:, None]
    t1 /= np.sqrt(np.einsum("ij,ij->i", t1, t1))[:, None]
    t2 = np.cross(normal, t1)
    return t1, t2


def cap(lam_t, lam_n, mu_s, mu_k):
    """The accumulated tangential impulse (k, 2) allowed by Coulomb's law.

    Static while the impulse needed to stop sliding stays within μ_s j_n;
    otherwise the contact slides and the impulse is μ_k j_n in the direction
    of the needed one (COURSE.md 5, friction as impulses)."""
    mag = np.sqrt(lam_t[:, 0] ** 2 + lam_t[:, 1] ** 2)
    stick = mag <= mu_s * lam_n
    scale = np.where(stick, 1.0, mu_k * lam_n / np.maximum(mag, _TINY))
    return lam_t * scale[:, None]
