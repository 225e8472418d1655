"""Restitution: which C_R a contact uses and when it is switched off (COURSE.md 5).

Each body has its own C_R, defined against a perfectly rigid, elastic object,
and the course writes the impulse on A with C_R of A and the impulse on B with
C_R of B. Against a static body (infinite mass, the floor) only the moving
body's C_R matters, and that is exactly what every rule below gives.

Between two moving bodies with different C_R, two different impulse
magnitudes on A and B would change the total momentum by (e_A − e_B) v_n / K
(K the course's denominator), against COURSE.md 6. So one impulse acts on
both, with a pair coefficient; the default `effective_mass` rule weights each
body's C_R by the share of the velocity change that body takes,
  K_A = 1/m_A + [(I_A⁻¹ (r_A × n)) × r_A]·n,  e = (K_A e_A + K_B e_B) / (K_A + K_B),
so a body much heavier than the other acts like the rigid object its partner's
C_R is defined against, and equal C_R give the course's formula unchanged.
Other rules: `mean`, `min`, `max` (the two bodies' values).

Resting contact: approach speeds below `restitution_threshold` get C_R = 0
so a box lying on the floor does not jitter; with `restitution_ramp` > 0 the
coefficient rises linearly from 0 to its value across that band instead.
"""
import numpy as np


def pair_restitution(model, a, b, k_a, k_b, rule):
    """(k,) combined C_R; k_a, k_b: each side's part of the normal's inverse effective mass."""
    eb = model.restitution[b]
    static_a = k_a <= 0.0
    if static_a.all():
        return eb           # every pair against the floor (or a sleeping body): see below
    ea = model.restitution[a]
    if rule == "mean":
        out = 0.5 * (ea + eb)
    elif rule == "min":
        out = np.minimum(ea, eb)
    elif rule == "max":
        out = np.maximum(ea, eb)
    else:
        total = k_a + k_b
        out = (k_a * ea + k_b * eb) / np.where(total > 0.0, total, 1.0)
    # a static (or sleeping) side is the rigid object the other's C_R refers to
    out = np.where(static_a, eb, np.where(k_b <= 0.0, ea, out))
    return out


def effective(e, approach_speed, threshold, ramp):
    """C_R after the resting-contact rule, for approach speeds (> 0 closing), m/s."""
    if ramp > 0.0:
        return e * np.clip((approach_speed - threshold) / ramp, 0.0, 1.0)
    return np.where(approach_speed > threshold, e, 0.0)
