"""Taking bodies whose state went non-finite out of the simulation.

When a stage leaves a NaN, an inf or a component beyond STATE_LIMIT
(NonFiniteStateError names the stage and the bodies), the caller can undo
the step (`restore` a `snapshot` taken before it), freeze the named bodies
where they were before the step (`frozen_model`: static, like a scene's
`static: true` body, so the others still collide with them) and step again.
One bad body then never stops the world. `World.reset()` returns to the
scene's own model, so a reset brings frozen bodies back.
"""
from dataclasses import replace

import numpy as np

from .model import frozen_array

# State fields a step changes, one row per body, and the flags beside them.
_ROWS = ("pos", "quat", "vel", "omega", "user_force", "user_force_offset", "user_torque",
         "impulse", "angular_impulse", "awake")
_FLAGS = ("time", "step_index", "has_pending_impulse", "has_user_force", "has_user_torque")
# Loads a frozen body lets go of (a held force would only push it again when reset).
_CLEARED = ("vel", "omega", "user_force", "user_force_offset", "user_torque", "impulse",
            "angular_impulse")


def snapshot(state):
    """Copies of what a step changes in `state` (rows and flags)."""
    return ({name: getattr(state, name).copy() for name in _ROWS},
            {name: getattr(state, name) for name in _FLAGS})


def restore(state, snap):
    """Put `state` back as `snapshot` found it (in place: the arrays stay the same objects)."""
    rows, flags = snap
    for name, saved in rows.items():
        getattr(state, name)[...] = saved
    for name, value in flags.items():
        setattr(state, name, value)


def frozen_model(model, indices):
    """`model` with the bodies `indices` static: no inverse mass or inertia, so
    no force, impulse or contact moves them."""
    idx = np.asarray(indices, dtype=np.int64)
    static = np.array(model.is_static)
    static[idx] = True
    inv_mass = np.array(model.inv_mass)
    inv_mass[idx] = 0.0
    inv_inertia = np.array(model.inv_inertia)
    inv_inertia[idx] = 0.0
    return replace(model, is_static=frozen_array(static, bool), inv_mass=frozen_array(inv_mass),
                   inv_inertia=frozen_array(inv_inertia))


def freeze_rows(state, indices):
    """Zero the frozen bodies' velocities and pending or held loads."""
    idx = np.asarray(indices, dtype=np.int64)
    for name in _CLEARED:
        getattr(state, name)[idx] = 0.0
    state.has_pending_impulse = bool(np.any(state.impulse) or np.any(state.angular_impulse))
