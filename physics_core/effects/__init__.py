"""Force effects: each a small factory `make(model)` returning `apply(kin, force, torque)`
that adds into the force and torque accumulators (MuJoCo's passive-force style).

Only effects the scene declares are built (promise 3): an undeclared effect
is not in the list and costs nothing.

Every effect module has the same four pieces: `constants(model)`, the tuple
of per-body (per-pair, per-spring) constants and scratch its kernel needs,
computed once; `unused()`, a tuple of the same types with no rows; `add(c,
pos, quat, vel, omega, force, torque)`, the compiled kernel that adds the
effect into the accumulators; and `make`, whose `apply` calls `add` with its
constants. integration.integration_data packs the same constants (or
`unused()` for an undeclared effect) for the compiled substep, so both paths
run the same kernel on the same numbers.
"""
from . import buoyancy, drag, gravitation, gravity, springs

ORDER = ("gravity", "gravitation", "drag", "buoyancy", "springs")
"""The fixed order in which declared effects add into F and τ."""
MODULES = {"gravity": gravity, "gravitation": gravitation, "drag": drag, "buoyancy": buoyancy,
           "springs": springs}


class Kinematics:
    """The body state a force is evaluated at (an integrator stage's trial state)."""
    __slots__ = ("pos", "quat", "vel", "omega")

    def __init__(self, pos, quat, vel, omega):
        self.pos, self.quat, self.vel, self.omega = pos, quat, vel, omega


def declared_effects(model):
    """The names of the effects this scene declares, in ORDER: gravity when its
    vector is not zero, springs when there are any, the others when named
    under `effects`."""
    on = {"gravity": model.gravity is not None and bool(model.gravity.any()),
          "gravitation": "gravitation" in model.effects,
          "drag": "drag" in model.effects,
          "buoyancy": "buoyancy" in model.effects,
          "springs": len(model.springs) > 0}
    return tuple(name for name in ORDER if on[name])


def build_force_effects(model):
    """[(name, apply)] in a fixed order, for the effects this scene declares."""
    return [(name, MODULES[name].make(model)) for name in declared_effects(model)]


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
