"""Force effects: each a small factory `make(model)` returning `apply(kin, force, torque)`
that adds into the force and torque accumulators (MuJoCo's passive-force style).

Only effects the scene declares are built (promise 3): an undeclared effect
is not in the list and costs nothing.

`make` computes the effect's per-body constants once; `apply` is a thin
wrapper over one compiled loop (Numba) over the bodies, pairs or springs
that adds into the accumulators.
"""
from . import buoyancy, drag, gravitation, gravity, springs


class Kinematics:
    """The body state a force is evaluated at (an integrator stage's trial state)."""
    __slots__ = ("pos", "quat", "vel", "omega")

    def __init__(self, pos, quat, vel, omega):
        self.pos, self.quat, self.vel, self.omega = pos, quat, vel, omega


def build_force_effects(model):
    """[(name, apply)] in a fixed order, for the effects this scene declares."""
    out = []
    if model.gravity is not None and model.gravity.any():
        out.append(("gravity", gravity.make(model)))
    if "gravitation" in model.effects:
        out.append(("gravitation", gravitation.make(model)))
    if "drag" in model.effects:
        out.append(("drag", drag.make(model)))
    if "buoyancy" in model.effects:
        out.append(("buoyancy", buoyancy.make(model)))
    if len(model.springs):
        out.append(("springs", springs.make(model)))
    return out


def potential_energy(model, state) -> float:
    """Potential energy (J) of the conservative effects in play (COURSE.md 6)."""
    total = 0.0
    if model.gravity is not None and model.gravity.any():
        total += gravity.potential(model, state)
    if "gravitation" in model.effects:
        total += gravitation.potential(model, state)
    if len(model.springs):
        total += springs.potential(model, state)
    return total
