"""Uniform gravity, W = m g (COURSE.md 2).

`constants(model)` is the per-body weight; `add` is the compiled kernel that
both `make`'s apply (World.forces) and integration.forces (the compiled
substep) call with it.
"""
import numpy as np
from numba import njit


@njit(cache=True)
def add_rows(force, weight):
    """force += weight, row by row (the weight of every body, 0 for static ones)."""
    for i in range(len(force)):
        for k in range(3):
            force[i, k] += weight[i, k]


def constants(model):
    """(weight,): m g per body, (n, 3) N, 0 for static bodies; computed once per model."""
    return (np.ascontiguousarray(np.where(model.is_static[:, None], 0.0, model.mass[:, None] * model.gravity)),)


def unused():
    """What integration_data packs when the scene has no gravity: the types of
    `constants`, no rows (so one compiled substep serves every scene)."""
    return (np.zeros((0, 3)),)


@njit(cache=True)
def add(c, pos, quat, vel, omega, force, torque):
    """The effect's kernel on the common signature of effects/: force += weight."""
    add_rows(force, c[0])


def make(model):
    """apply(kin, force, torque): `add` with this model's constants (World.forces' path)."""
    c = constants(model)

    def apply(kin, force, torque):
        add(c, kin.pos, kin.quat, kin.vel, kin.omega, force, torque)
    return apply


def potential(model, state) -> float:
    """U = -Σ m g·x over dynamic bodies."""
    m = np.where(model.is_static, 0.0, model.mass)
    return float(-np.sum(m * (state.pos @ model.gravity)))
