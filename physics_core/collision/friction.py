"""Friction at contacts (COURSE.md 2 and 5): coefficients, tangent plane, static/kinetic cap.

Static or kinetic is decided per contact and substep from how fast it was
slipping at the end of the last substep's solve (`static_friction_speed`;
the slip now would count the push this substep's forces just gave a resting
contact; a new contact starts static for one substep, which at worst holds a
contact that lands sliding with μ_s instead of μ_k that once). Within the
solve the friction impulse is then bounded by μ_s λ_n (sticking) or μ_k λ_n
(sliding, directed against the slip). Deciding inside the
iterations instead, on the impulse the solver happens to ask for, lets one
point of a box on an incline flip to kinetic, pass its load to the others,
and the whole box creep where it should stand.

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


def cap(lam_t, lam_n, mu, sliding, slip_velocity):
    """The accumulated tangential impulse (k, 2) allowed by Coulomb's law,
    |λ_t| ≤ μ λ_n. A larger one is brought back onto the cone: for a contact
    that is sliding (`sliding`, kinetic friction) it becomes μ_k λ_n against
    the slip velocity (k, 2), the course's kinetic impulse μ_k j along −t with
    t the unit tangential relative velocity; for a sticking contact it keeps
    the direction of the impulse that would stop it (the static bound)."""
    mag2 = np.einsum("ij,ij->i", lam_t, lam_t)
    lim = mu * lam_n
    over = mag2 > lim * lim
    if not over.any():
        return lam_t
    out = lam_t.copy()
    o = np.flatnonzero(over)
    mag = np.sqrt(mag2[o])
    direction = lam_t[o] / mag[:, None]
    v = slip_velocity[o]
    speed = np.sqrt(np.einsum("ij,ij->i", v, v))
    against = sliding[o] & (speed > _TINY)
    if against.any():
        direction[against] = -v[against] / speed[against, None]
    out[o] = lim[o, None] * direction
    return out
