"""A frozen copy of the compiled integrate stage as it was at commit 76bcc0d,
before integrate_substep (physics_core/integration.py) took it over.

Test-only reference for tests/test_integration_loop.py: physics_core's
integrators.py (a Python wrapper per integrator that calls `sys.forces` and
then compiled update loops over bodies) and effects/*.py (one `make(model)`
per effect returning `apply(kin, F, T)` over one compiled kernel), copied
file for file with their relative imports made absolute, and `System`,
the integrate stage of that commit's World (its `_build`, the integrate part
of `_step_once` and `forces`), so the reference does not depend on the World
of today. The one-body helpers they call (quaternion.py, free_rotation.py,
vec3.py) are the engine's own. A System steps exactly as the World did
before the port (COURSE.md 2 and 4).
"""
from types import SimpleNamespace

import numpy as np

from physics_core import quaternion as qt
from physics_core.effects import Kinematics
from physics_core.free_rotation import RowSplit, isotropic_rows
from physics_core.shapes import BOX
from physics_core.vec3 import cross

from . import buoyancy, drag, gravitation, gravity, springs
from .integrators import INTEGRATORS

LOAD_FIELDS = ("pos", "quat", "vel", "omega", "user_force", "user_force_offset", "user_torque")


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


class System:
    """The integrate stage of commit 76bcc0d's World, on copies of a World's
    state, loads and (awake) masses; `substep(h)` is one pass of its substep
    loop without contacts: the `rotating` test, then the integrator."""

    def __init__(self, world):
        m = self.model = world.model
        s = world.state
        self.state = SimpleNamespace(has_user_force=bool(s.has_user_force), has_user_torque=bool(s.has_user_torque),
                                     **{k: np.array(getattr(s, k)) for k in LOAD_FIELDS})
        self.inv_mass = (m.inv_mass * s.awake)[:, None]
        self.inv_inertia = m.inv_inertia * s.awake[:, None]
        self.inertia = m.inertia
        self.rotation_rows = RowSplit(isotropic_rows(m.inertia))
        self.substeps = world.substeps
        self._timed_effects = [("force:" + name, apply) for name, apply in build_force_effects(m)]
        self._integrate = INTEGRATORS[m.integrator]
        self._model_torque = bool(springs.makes_torque(m)
                                  or ("buoyancy" in m.effects and np.any(m.shape_type == BOX)))

    def substep(self, h):
        s = self.state
        self.rotating = bool(self._model_torque or s.has_user_torque or s.omega.any())
        self._integrate(self, h)

    def forces(self, pos, quat, vel, omega):
        """Net force and torque (world frame) on every body at a trial state."""
        F = np.zeros_like(pos)
        T = np.zeros_like(pos)
        kin = Kinematics(pos, quat, vel, omega)
        for _, apply in self._timed_effects:
            apply(kin, F, T)
        s = self.state
        if s.has_user_force:
            F += s.user_force
        if s.has_user_torque:
            T += s.user_torque + cross(qt.rotate(quat, s.user_force_offset), s.user_force)
        return F, T
