"""Hooke springs with dampers between attachment points (COURSE.md 2).

F_a = [K (l − l₀) + C (v_pb − v_pa)·u] u with u = (p_b − p_a)/l, opposite on
b, each applied at its attachment point so an off-centre spring also
produces torque τ = r × F. The damper acts along the spring (a dashpot);
for motion along the spring this is the course's F_A = −C (v_A − v_B).
A spring of zero length has no direction and exerts K·d = 0.

Stiff springs and explicit steps: a spring of stiffness K on an effective
mass m_eff oscillates at ω = √(K/m_eff); the step-by-step integrators are
only stable for ω h below a limit (2 for semi-implicit Euler and velocity
Verlet, 2.83 for RK4) and only accurate well below it. `stable_substeps`
gives the sub-step count that keeps ω h ≤ MAX_OMEGA_H and the damper's rate
(C/m_eff) h ≤ MAX_DAMPING_H for the stiffest spring; the World runs that many
internal sub-steps. Explicit Euler grows an undamped oscillation by
√(1 + ω²h²) every step whatever h is: sub-steps slow the growth but cannot
stop it, so stiff undamped springs need another integrator.
"""
import math
import warnings

import numpy as np

from .. import quaternion as qt
from ..vec3 import cross, dot

MAX_OMEGA_H = 0.5       # rad per sub-step: stable with margin; period error ≈ (ω h)²/24 ≤ 1 %
MAX_DAMPING_H = 0.5     # (C/m_eff) h: the damper removes at most about half the relative speed per sub-step
MAX_SPRING_SUBSTEPS = 1000


def effective_inverse_mass(model):
    """Upper bound of 1/m_eff each spring sees along its line, per spring (1/kg).

    At an attachment offset r the inverse mass along a unit direction u is
    1/m + (r × u)·I_w⁻¹ (r × u) ≤ 1/m + |r|² max(I⁻¹) (COURSE.md 5's impulse
    denominator); the two ends add. World and static ends count as infinite mass."""
    s = model.springs
    total = np.zeros(len(s))
    for body, local in ((s.a, s.point_a), (s.b, s.point_b)):
        on_body = body >= 0
        i = np.where(on_body, body, 0)
        inv_m = np.where(on_body, model.inv_mass[i], 0.0)
        inv_i = np.where(on_body, model.inv_inertia[i].max(axis=1), 0.0)
        total += inv_m + np.einsum("ij,ij->i", local, local) * inv_i
    return total


def stable_substeps(model, dt) -> int:
    """Sub-steps per step of length dt keeping ω h ≤ MAX_OMEGA_H and (C/m_eff) h ≤ MAX_DAMPING_H
    for every spring (1 without springs); capped at MAX_SPRING_SUBSTEPS with a warning."""
    if not len(model.springs):
        return 1
    inv_m = effective_inverse_mass(model)
    s = model.springs
    omega = np.sqrt(s.stiffness * inv_m)                 # rad/s
    rate = s.damping * inv_m                             # 1/s
    need = max(float(omega.max()) * dt / MAX_OMEGA_H, float(rate.max()) * dt / MAX_DAMPING_H, 1.0)
    n = math.ceil(need - 1e-9)
    if n > MAX_SPRING_SUBSTEPS:
        warnings.warn(f"the stiffest spring needs {n} sub-steps per step of {dt} s "
                      f"(ω = {float(omega.max()):.4g} rad/s); using {MAX_SPRING_SUBSTEPS}: "
                      "lower dt or the stiffness", RuntimeWarning, stacklevel=3)
        n = MAX_SPRING_SUBSTEPS
    return n


class _End:
    """One end (a or b) of every spring: which body, and where on it.

    A world end (index -1) holds its world point in `fixed`; a body end its
    body-frame offset in `local`. `turns` is false when every body end is at
    a centre of mass, so the rotations and r × F are skipped."""

    def __init__(self, model, body, local):
        self.on_body = body >= 0
        self.all_bodies = bool(self.on_body.all())      # common cases skip the masking
        self.no_body = not self.on_body.any()
        self.row = np.where(self.on_body, body, 0)
        self.mask = self.on_body[:, None].astype(float)
        self.local = np.where(self.on_body[:, None], local, 0.0)
        self.fixed = np.where(self.on_body[:, None], 0.0, local)
        self.still = np.zeros_like(self.fixed)
        self.turns = bool(np.any(self.local))
        self.bodies = self.row[self.on_body]

    def points(self, kin):
        """World attachment points, offsets from the centres (m) and point velocities (m/s)."""
        if self.no_body:
            return self.fixed, None, self.still
        i = self.row
        point = kin.pos[i]
        vel = kin.vel[i]
        arm = None
        if self.turns:
            arm = qt.rotate(kin.quat[i], self.local)
            vel = vel + cross(kin.omega[i], arm)
        if not self.all_bodies:
            point = point * self.mask + self.fixed
            vel = vel * self.mask
            if arm is not None:
                arm = arm * self.mask
        return (point + arm if arm is not None else point), arm, vel

    def accumulate(self, out, value):
        """out[body] += value for the ends on bodies (several springs may share a body)."""
        if self.no_body:
            return
        np.add.at(out, self.bodies, value if self.all_bodies else value[self.on_body])


def _ends(model):
    s = model.springs
    return _End(model, s.a, s.point_a), _End(model, s.b, s.point_b)


def makes_torque(model) -> bool:
    """Whether some spring is attached away from a body's centre of mass (τ = r × F)."""
    return any(end.turns for end in _ends(model)) if len(model.springs) else False


def make(model):
    s = model.springs
    k, l0, c = s.stiffness, s.rest_length, s.damping
    end_a, end_b = _ends(model)
    damped = bool(np.any(c))

    def apply(kin, force, torque):
        pa, ra, va = end_a.points(kin)
        pb, rb, vb = end_b.points(kin)
        d = pb - pa
        length = np.sqrt(dot(d, d))
        u = d / np.where(length > 0, length, 1.0)[:, None]
        tension = k * (length - l0)
        if damped:
            tension = tension + c * dot(vb - va, u)
        f = tension[:, None] * u
        end_a.accumulate(force, f)
        end_b.accumulate(force, -f)
        if ra is not None:
            end_a.accumulate(torque, cross(ra, f))
        if rb is not None:
            end_b.accumulate(torque, cross(rb, -f))
    return apply


def potential(model, state) -> float:
    """U = Σ ½ K (l − l₀)²."""
    from . import Kinematics
    kin = Kinematics(state.pos, state.quat, state.vel, state.omega)
    end_a, end_b = _ends(model)
    length = np.linalg.norm(end_b.points(kin)[0] - end_a.points(kin)[0], axis=1)
    s = model.springs
    return float(np.sum(0.5 * s.stiffness * (length - s.rest_length) ** 2))
