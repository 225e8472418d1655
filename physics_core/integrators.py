"""The four integrators a scene can pick (COURSE.md 4), advancing one (sub)step h.

Each `INTEGRATORS[name](sys, h)` is a thin Python wrapper over the one
compiled implementation, integration.integrate_substep: explicit and
semi-implicit Euler evaluate the forces once, velocity Verlet twice, RK4
four times, all inside the compiled call, with the declared force effects'
kernels (effects/*.py) and the held loads exactly as World.forces adds them.
The integrators themselves (state (x, q, v, L), the torque-free splitting,
the exact orientation map) are described in integrator_kernels.py.

`sys` is a World (or anything with its attributes): its state arrays are
updated in place; `sys.model` gives the force constants (integration_data,
built once per model and sys), `sys.rotation_rows` the isotropic bodies,
`sys.inv_mass` (n, 1), `sys.inertia` and `sys.inv_inertia` (n, 3) the awake
bodies' masses. The rotational half runs when integrate_substep finds it
needed (an effect that can make torque, a held torque, a spinning body),
or when `sys.rotating` says so if sys sets it. When sys keeps a `_prof`
dict, each effect's seconds are added to `_prof["force:<name>"]`.
The World's compiled step (step_loop.py) calls integrate_substep itself.
"""
import weakref

import numpy as np

from . import free_rotation
from .cycle_clock import seconds_per_cycle
from .integration import (EFFECT_NAMES, FLAGS, INTEGRATOR_CODES, can_make_torque, integrate_substep,
                          integration_data, integration_profile, integration_work)


def angular_momentum(q, inertia, omega, rows=None):
    """L = I_w ω; `rows` (free_rotation.RowSplit) lets isotropic bodies skip
    the two frame changes (I_w = I 1 for them)."""
    return free_rotation.world_momentum(q, inertia, omega, _mask(rows, len(q)))


def angular_velocity(q, inv_inertia, L, rows=None):
    """ω = I_w⁻¹ L, with the same isotropic shortcut as angular_momentum."""
    return free_rotation.world_velocity(q, inv_inertia, L, _mask(rows, len(q)))


def _mask(rows, n):
    """Per-body isotropic flags of a RowSplit (or a bool array); none without one."""
    if rows is None:
        return np.zeros(n, dtype=bool)
    return rows.mask if isinstance(rows, free_rotation.RowSplit) else free_rotation.RowSplit(rows).mask


class _Prepared:
    """What the wrappers keep per World: the data of its model and rows, the
    scratch for its body count, and the profile array with the declared
    effects' keys, and whether an effect can make torque."""
    __slots__ = ("model", "rows", "n", "data", "work", "prof", "timed", "model_torque")

    def __init__(self, model, rows, n):
        self.model, self.rows, self.n = model, rows, n
        self.model_torque = can_make_torque(model)
        self.data = integration_data(model, isotropic=_mask(rows, n))
        self.work = integration_work(n)
        self.prof = integration_profile()
        flags = self.data[FLAGS]
        self.timed = [(e, "force:" + name) for e, name in enumerate(EFFECT_NAMES) if flags[e]]


_PREPARED = weakref.WeakKeyDictionary()


def _prepared(sys):
    """The World's _Prepared, rebuilt when its model, rows or body count changed."""
    rows, n = getattr(sys, "rotation_rows", None), len(sys.state.pos)
    p = _PREPARED.get(sys)
    if p is None or p.model is not sys.model or p.rows is not rows or p.n != n:
        p = _PREPARED[sys] = _Prepared(sys.model, rows, n)
    return p


def _substep(code, sys, h):
    """integrate_substep on the World's arrays; the effects' cycles into sys._prof."""
    p = _prepared(sys)
    s = sys.state
    p.prof[:] = 0
    turns = bool(getattr(sys, "rotating", p.model_torque))
    integrate_substep(code, float(h), p.data, s.pos, s.quat, s.vel, s.omega, sys.inv_mass[:, 0],
                      sys.inertia, sys.inv_inertia, s.user_force, s.user_force_offset, s.user_torque,
                      bool(s.has_user_force), bool(s.has_user_torque), turns, p.work, p.prof)
    prof = getattr(sys, "_prof", None)
    if prof is not None:
        for e, key in p.timed:
            prof[key] = prof.get(key, 0.0) + float(p.prof[e]) * seconds_per_cycle()


def explicit_euler(sys, h):
    """x ← x + v h, v ← v + a h; q turned by the start-of-step ω."""
    _substep(INTEGRATOR_CODES["explicit_euler"], sys, h)


def semi_implicit_euler(sys, h):
    """v ← v + a h, then x ← x + v h with the new v (symplectic Euler)."""
    _substep(INTEGRATOR_CODES["semi_implicit_euler"], sys, h)


def velocity_verlet(sys, h):
    """Kick ½h, drift h, kick ½h with the forces at the new positions."""
    _substep(INTEGRATOR_CODES["velocity_verlet"], sys, h)


def rk4(sys, h):
    """Classical fourth-order Runge–Kutta on (x, q, v, L); forces re-evaluated at each stage."""
    _substep(INTEGRATOR_CODES["rk4"], sys, h)


INTEGRATORS = {
    "explicit_euler": explicit_euler,
    "semi_implicit_euler": semi_implicit_euler,
    "velocity_verlet": velocity_verlet,
    "rk4": rk4,
}
