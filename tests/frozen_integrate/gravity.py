# Frozen copy of physics_core/effects/gravity.py at commit 76bcc0d (see __init__.py); imports made absolute.
"""Uniform gravity, W = m g (COURSE.md 2)."""
import numpy as np
from numba import njit


@njit(cache=True)
def add_rows(force, weight):
    """force += weight, row by row (the weight of every body, 0 for static ones)."""
    for i in range(len(force)):
        for k in range(3):
            force[i, k] += weight[i, k]


def make(model):
    weight = np.ascontiguousarray(np.where(model.is_static[:, None], 0.0, model.mass[:, None] * model.gravity))

    def apply(kin, force, torque):
        add_rows(force, weight)
    return apply


def potential(model, state) -> float:
    """U = -Σ m g·x over dynamic bodies."""
    m = np.where(model.is_static, 0.0, model.mass)
    return float(-np.sum(m * (state.pos @ model.gravity)))
