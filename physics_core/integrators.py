"""The four integrators a scene can pick (COURSE.md 4), advancing one (sub)step h.

State y = (x, q, v, L): position, orientation, velocity and world angular
momentum L = I_w ω with I_w = R diag(I) Rᵀ. Working with L makes the
gyroscopic term exact: with no torque L stays constant whatever the
integrator, and ω = I_w⁻¹ L follows the orientation, which gives the
intermediate-axis flip of an asymmetric body (COURSE.md 3). Orientation is
advanced by the exact exponential map of ω h, so it stays a unit quaternion;
semi-implicit Euler and velocity Verlet advance it by the torque-free
splitting of free_rotation.py between torque kicks, so that, like their
translational update, they keep the energy of a free body bounded.

Each integrator calls `sys.forces(x, q, v, ω) -> (F, τ)` as often as its
order needs (1 for the Euler pair, 2 for velocity Verlet, 4 for RK4).
When no body spins and nothing can apply torque, the rotational half is
skipped (`sys.rotating` false). `sys.rotation_rows` (free_rotation.RowSplit)
names the isotropic bodies: for them I_w = I 1, so L = I ω and ω = L / I
need no change of frame, and their orientation follows the exact map.
"""
import numpy as np

from . import free_rotation
from . import quaternion as qt


def angular_momentum(q, inertia, omega, rows=None):
    """L = I_w ω; `rows` (free_rotation.RowSplit) lets isotropic bodies skip
    the two frame changes (I_w = I 1 for them)."""
    if rows is None:
        return qt.rotate(q, inertia * qt.rotate_inverse(q, omega))
    return free_rotation.world_momentum(q, inertia, omega, rows)


def angular_velocity(q, inv_inertia, L, rows=None):
    """ω = I_w⁻¹ L, with the same isotropic shortcut as angular_momentum."""
    if rows is None:
        return qt.rotate(q, inv_inertia * qt.rotate_inverse(q, L))
    return free_rotation.world_velocity(q, inv_inertia, L, rows)


def explicit_euler(sys, h):
    s = sys.state
    F, T = sys.forces(s.pos, s.quat, s.vel, s.omega)
    s.pos += s.vel * h
    s.vel += F * sys.inv_mass * h
    if sys.rotating:
        L = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + T * h
        s.quat = free_rotation.turn(s.quat, s.omega, h)
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L, sys.rotation_rows)


def semi_implicit_euler(sys, h):
    """v ← v + a h, then x ← x + v h with the new v (symplectic Euler)."""
    s = sys.state
    F, T = sys.forces(s.pos, s.quat, s.vel, s.omega)
    s.vel += F * sys.inv_mass * h
    s.pos += s.vel * h
    if sys.rotating:
        L = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + T * h
        s.quat, s.omega = free_rotation.advance(s.quat, L, sys.inv_inertia, h, sys.rotation_rows)


def velocity_verlet(sys, h):
    """Kick ½h, drift h, kick ½h with the forces at the new positions.

    Velocity-dependent forces (drag, dampers) at the end point see the
    predicted velocity v + a h."""
    s = sys.state
    F0, T0 = sys.forces(s.pos, s.quat, s.vel, s.omega)
    a0 = F0 * sys.inv_mass
    v_half = s.vel + 0.5 * h * a0
    s.pos += v_half * h
    if sys.rotating:
        L_half = angular_momentum(s.quat, sys.inertia, s.omega, sys.rotation_rows) + 0.5 * h * T0
        s.quat, _ = free_rotation.advance(s.quat, L_half, sys.inv_inertia, h, sys.rotation_rows)
        omega_pred = angular_velocity(s.quat, sys.inv_inertia, L_half + 0.5 * h * T0, sys.rotation_rows)
    else:
        omega_pred = s.omega
    F1, T1 = sys.forces(s.pos, s.quat, v_half + 0.5 * h * a0, omega_pred)
    s.vel = v_half + 0.5 * h * F1 * sys.inv_mass
    if sys.rotating:
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L_half + 0.5 * h * T1, sys.rotation_rows)


def rk4(sys, h):
    """Classical fourth-order Runge–Kutta on (x, q, v, L); forces re-evaluated at each stage."""
    s = sys.state
    x0, q0, v0 = s.pos, s.quat, s.vel
    rot = sys.rotating
    L0 = angular_momentum(q0, sys.inertia, s.omega, sys.rotation_rows) if rot else None

    def deriv(x, q, v, L):
        if rot:
            q = qt.normalize(q)
            w = angular_velocity(q, sys.inv_inertia, L, sys.rotation_rows)
        else:
            w = s.omega
        F, T = sys.forces(x, q, v, w)
        dq = qt.derivative(q, w) if rot else None
        return v, dq, F * sys.inv_mass, T

    k1 = deriv(x0, q0, v0, L0)
    k2 = deriv(*_trial(x0, q0, v0, L0, k1, 0.5 * h, rot))
    k3 = deriv(*_trial(x0, q0, v0, L0, k2, 0.5 * h, rot))
    k4 = deriv(*_trial(x0, q0, v0, L0, k3, h, rot))
    w = h / 6.0
    s.pos = x0 + w * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    s.vel = v0 + w * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    if rot:
        s.quat = qt.normalize(q0 + w * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]))
        L = L0 + w * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])
        s.omega = angular_velocity(s.quat, sys.inv_inertia, L, sys.rotation_rows)


def _trial(x0, q0, v0, L0, k, c, rot):
    return (x0 + c * k[0], q0 + c * k[1] if rot else q0, v0 + c * k[2],
            L0 + c * k[3] if rot else None)


INTEGRATORS = {
    "explicit_euler": explicit_euler,
    "semi_implicit_euler": semi_implicit_euler,
    "velocity_verlet": velocity_verlet,
    "rk4": rk4,
}
