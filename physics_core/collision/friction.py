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

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum

_TINY = 1e-300


def coefficients(model, a, b):
    """(μ_s, μ_k) per contact from the material pair table, either order (COURSE.md 2)."""
    ma, mb = model.material[a], model.material[b]
    return model.mu_static[ma, mb], model.mu_kinetic[ma, mb]


def tangent_basis(normal):
    """(t1, t2), each (k, 3): an orthonormal basis of the plane ⟂ n, from n
    alone (Duff et al. 2017, "Building an orthonormal basis, revisited":
    branch-free, continuous except across n_z = 0, never NaN for a unit n)."""
    D = tangent_frame(normal)
    return D[:, 1], D[:, 2]


def tangent_frame(normal):
    """(k, 3, 3) rows n, t1, t2: the normal and tangent_basis' two tangents
    (a view of tangent_frame_last's array)."""
    return tangent_frame_last(normal).transpose(2, 0, 1)


def tangent_frame_last(normal):
    """tangent_frame with the contacts on the last axis: (3 rows, 3, k), C-ordered."""
    nx, ny, nz = normal[:, 0], normal[:, 1], normal[:, 2]
    D = np.empty((3, 3, len(normal)))
    D[0] = normal.T
    sign = np.copysign(1.0, nz)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    D[1, 0] = 1.0 + sign * nx * nx * a
    D[1, 1] = sign * b
    D[1, 2] = -sign * nx
    D[2, 0] = b
    D[2, 1] = sign + ny * ny * a
    D[2, 2] = -ny
    return D


def cap(lam_t, lam_n, mu, sliding, slip_velocity):
    """The accumulated tangential impulse (k, 2) allowed by Coulomb's law,
    |λ_t| ≤ μ λ_n. A larger one is brought back onto the cone: for a contact
    that is sliding (`sliding`, kinetic friction) it becomes μ_k λ_n against
    the slip velocity, the course's kinetic impulse μ_k j along −t with t the
    unit tangential relative velocity; for a sticking contact it keeps the
    direction of the impulse that would stop it (the static bound).
    `slip_velocity()` gives the (k, 2) slip velocities, or None when no row
    is sliding; it is only called when some row is over its bound."""
    mag2 = _einsum("ij,ij->i", lam_t, lam_t)
    lim = mu * lam_n
    over = mag2 > lim * lim
    if not np.count_nonzero(over):
        return lam_t
    v = slip_velocity()
    if v is None:
        return lam_t * np.where(over, lim / np.sqrt(mag2 + _TINY), 1.0)[:, None]
    direction = np.where(sliding[:, None], -v, lam_t)
    scale = np.where(over, lim / np.sqrt(_einsum("ij,ij->i", direction, direction) + _TINY), 1.0)
    return np.where(over[:, None], direction * scale[:, None], lam_t)
