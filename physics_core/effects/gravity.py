"""Uniform gravity, W = m g (COURSE.md 2)."""
import numpy as np


def make(model):
    weight = np.where(model.is_static[:, None], 0.0, model.mass[:, None] * model.gravity)

    def apply(kin, force, torque):
        force += weight
    return apply


def potential(model, state) -> float:
    """U = -Σ m g·x over dynamic bodies."""
    m = np.where(model.is_static, 0.0, model.mass)
    return float(-np.sum(m * (state.pos @ model.gravity)))
