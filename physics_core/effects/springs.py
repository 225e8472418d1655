"""Hooke springs with dampers between attachment points (COURSE.md 2).

F_a = [K (l − l₀) + C (v_pb − v_pa)·u] u with u = (p_b − p_a)/l, opposite on
b, each applied at its attachment point so an off-centre spring also
produces torque τ = r × F. The damper acts along the spring (a dashpot);
for motion along the spring this is the course's F_A = −C (v_A − v_B).
A spring of zero length has no direction and exerts K·d = 0.
"""
import numpy as np

from .. import quaternion as qt


def _ends(model, kin):
    """World attachment points, their offsets and point velocities for both ends.

    Index -1 is the world: an extra row with zero pose and velocity is appended."""
    s = model.springs
    n = model.n
    pos = np.vstack([kin.pos, np.zeros((1, 3))])
    quat = np.vstack([kin.quat, [[1.0, 0.0, 0.0, 0.0]]])
    vel = np.vstack([kin.vel, np.zeros((1, 3))])
    omega = np.vstack([kin.omega, np.zeros((1, 3))])
    out = []
    for body, local in ((s.a, s.point_a), (s.b, s.point_b)):
        i = np.where(body < 0, n, body)
        arm = qt.rotate(quat[i], local)
        out.append((i, pos[i] + arm, arm, vel[i] + np.cross(omega[i], arm)))
    return out


def make(model):
    s = model.springs
    n = model.n
    k, l0, c = s.stiffness, s.rest_length, s.damping

    def apply(kin, force, torque):
        (ia, pa, ra, va), (ib, pb, rb, vb) = _ends(model, kin)
        d = pb - pa
        length = np.sqrt(np.einsum("ij,ij->i", d, d))
        u = d / np.where(length > 0, length, 1.0)[:, None]
        rel_speed = np.einsum("ij,ij->i", vb - va, u)
        f = (k * (length - l0) + c * rel_speed)[:, None] * u
        fa = np.zeros((n + 1, 3))
        ta = np.zeros((n + 1, 3))
        np.add.at(fa, ia, f)
        np.add.at(fa, ib, -f)
        np.add.at(ta, ia, np.cross(ra, f))
        np.add.at(ta, ib, np.cross(rb, -f))
        force += fa[:n]
        torque += ta[:n]
    return apply


def potential(model, state) -> float:
    """U = Σ ½ K (l − l₀)²."""
    from . import Kinematics
    kin = Kinematics(state.pos, state.quat, state.vel, state.omega)
    (_, pa, _, _), (_, pb, _, _) = _ends(model, kin)
    length = np.linalg.norm(pb - pa, axis=1)
    s = model.springs
    return float(np.sum(0.5 * s.stiffness * (length - s.rest_length) ** 2))
