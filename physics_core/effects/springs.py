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

The forces are one compiled loop over the springs (`spring_forces`), then
one over each end adding them to the bodies in spring order; the pulls and
lever arms go through scratch arrays made once with the constants
(`constants`), so an evaluation allocates nothing.
"""
import math
import warnings

import numpy as np
from numba import njit

from .. import quaternion as qt
from ..quaternion import cross_one, rotate_one, row3, row4
from ..vec3 import cross

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


_ZERO3 = (0.0, 0.0, 0.0)


@njit(cache=True)
def _end_state(on_body, turns, local, fixed, p, q, v, w):
    """World point, arm from the body's centre and velocity of one spring end,
    from the body's pose (p, q) and velocities (v, ω); a world end is its fixed
    point, at rest. Tuples only: no array passes through the per-spring call."""
    if not on_body:
        return fixed, _ZERO3, _ZERO3
    if not turns:
        return p, _ZERO3, v
    arm = rotate_one(q, local)
    spin = cross_one(w, arm)
    return ((p[0] + arm[0], p[1] + arm[1], p[2] + arm[2]), arm,
            (v[0] + spin[0], v[1] + spin[1], v[2] + spin[2]))


@njit(cache=True)
def _at(a, e, s):
    """a[e, s] of an (2, m, 3) array as a 3-tuple."""
    return (a[e, s, 0], a[e, s, 1], a[e, s, 2])


@njit(cache=True)
def _pull(pa, va, pb, vb, k, l0, c, damped):
    """F_a = [K (l − l₀) + C (v_pb − v_pa)·u] u, u = (p_b − p_a)/l (0 for l = 0)."""
    d = (pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2])
    length = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    scale = length if length > 0 else 1.0
    u = (d[0] / scale, d[1] / scale, d[2] / scale)
    tension = k * (length - l0)
    if damped:
        tension = tension + c * ((vb[0] - va[0]) * u[0] + (vb[1] - va[1]) * u[1] + (vb[2] - va[2]) * u[2])
    return (tension * u[0], tension * u[1], tension * u[2])


@njit(cache=True)
def _add_to_bodies(out, body, f, sign):
    """out[body[s]] += sign f[s] over the springs whose end is on a body, in spring order."""
    for s in range(len(body)):
        if body[s] >= 0:
            for k in range(3):
                out[body[s], k] += sign * f[s, k]


@njit(cache=True)
def _add_torques(out, body, arm, f, sign):
    """out[body[s]] += arm[s] × (sign f[s]) over the springs whose end is on a body."""
    for s in range(len(body)):
        if body[s] >= 0:
            t = cross_one(row3(arm, s), (sign * f[s, 0], sign * f[s, 1], sign * f[s, 2]))
            for k in range(3):
                out[body[s], k] += t[k]


@njit(cache=True)
def spring_forces(body, local, fixed, turns, stiffness, rest, damping, damped, pos, quat, vel, omega,
                  force, torque, f, arm):
    """Every spring's pull, then F and τ = r × F added at each end (a: +F, b: −F).
    f (m, 3) and arm (2, m, 3): scratch for the pulls and lever arms, overwritten."""
    m = body.shape[1]
    for s in range(m):
        i, j = max(body[0, s], 0), max(body[1, s], 0)        # a world end reads row 0, unused
        pa, ra, va = _end_state(body[0, s] >= 0, turns[0], _at(local, 0, s), _at(fixed, 0, s), row3(pos, i),
                                row4(quat, i), row3(vel, i), row3(omega, i))
        pb, rb, vb = _end_state(body[1, s] >= 0, turns[1], _at(local, 1, s), _at(fixed, 1, s), row3(pos, j),
                                row4(quat, j), row3(vel, j), row3(omega, j))
        f[s, 0], f[s, 1], f[s, 2] = _pull(pa, va, pb, vb, stiffness[s], rest[s], damping[s], damped)
        arm[0, s, 0], arm[0, s, 1], arm[0, s, 2] = ra
        arm[1, s, 0], arm[1, s, 1], arm[1, s, 2] = rb
    _add_to_bodies(force, body[0], f, 1.0)
    _add_to_bodies(force, body[1], f, -1.0)
    if turns[0]:
        _add_torques(torque, body[0], arm[0], f, 1.0)
    if turns[1]:
        _add_torques(torque, body[1], arm[1], f, -1.0)


def constants(model):
    """(body, local, fixed, turns, K, l₀, C, damped, f, arm): each spring's end
    bodies (2, m) (-1: the world), body-frame offsets and world points of its
    ends (2, m, 3), whether either end is off a centre of mass, stiffness, rest
    length and damping (m,), and the kernel's scratch f (m, 3), arm (2, m, 3)."""
    s = model.springs
    ends = _ends(model)
    body = np.ascontiguousarray(np.stack([np.where(e.on_body, e.row, -1) for e in ends]), dtype=np.int64)
    local = np.ascontiguousarray(np.stack([e.local for e in ends]), dtype=float)
    fixed = np.ascontiguousarray(np.stack([e.fixed for e in ends]), dtype=float)
    turns = np.array([e.turns for e in ends], dtype=bool)
    k, l0, c = (np.array(a, dtype=float) for a in (s.stiffness, s.rest_length, s.damping))   # own copies
    m = len(s)
    return body, local, fixed, turns, k, l0, c, bool(np.any(c)), np.zeros((m, 3)), np.zeros((2, m, 3))


def unused():
    """The types of `constants` with no springs, for a scene without them."""
    none = np.zeros(0)
    return (np.zeros((2, 0), dtype=np.int64), np.zeros((2, 0, 3)), np.zeros((2, 0, 3)), np.zeros(2, dtype=bool),
            none, none.copy(), none.copy(), False, np.zeros((0, 3)), np.zeros((2, 0, 3)))


@njit(cache=True)
def add(c, pos, quat, vel, omega, force, torque):
    """The effect's kernel on the common signature of effects/."""
    body, local, fixed, turns, k, l0, damping, damped, f, arm = c
    spring_forces(body, local, fixed, turns, k, l0, damping, damped, pos, quat, vel, omega, force, torque, f, arm)


def make(model):
    """apply(kin, force, torque): `add` with this model's constants (World.forces' path)."""
    c = constants(model)

    def apply(kin, force, torque):
        add(c, kin.pos, kin.quat, kin.vel, kin.omega, force, torque)
    return apply


def potential(model, state) -> float:
    """U = Σ ½ K (l − l₀)²."""
    from . import Kinematics
    kin = Kinematics(state.pos, state.quat, state.vel, state.omega)
    end_a, end_b = _ends(model)
    length = np.linalg.norm(end_b.points(kin)[0] - end_a.points(kin)[0], axis=1)
    s = model.springs
    return float(np.sum(0.5 * s.stiffness * (length - s.rest_length) ** 2))
