"""Restitution: the bounce pass after the solve (COURSE.md 5, coefficient of restitution).

Driven by the approach speed stored before the solve, u0_n < 0 (Box2D's
restitution stage): a contact that was pushed (λ_n > 0) and approached
faster than `restitution_threshold` is driven to the separation speed
C_R × approach. Below the threshold C_R is 0 (resting contact: a box lying
on the floor does not jitter); with `restitution_ramp` > 0 it rises linearly
from 0 over that band instead.

Time of collision (COURSE.md 5): the surfaces met a fraction τ of the
substep in, where s0 = approach·h − depth had closed; the bodies move with
the old velocity until then and with the new one after (push_out.py).
"""
from numba import njit

from .contact_layout import DEPTH, E, LAM, U0


@njit(cache=True)
def effective_restitution(e, approach, threshold, ramp):
    """C_R after the resting-contact rule, for an approach speed (> 0 closing)."""
    if ramp > 0.0:
        return e * min(max((approach - threshold) / ramp, 0.0), 1.0)
    return e if approach > threshold else 0.0


@njit(cache=True)
def bounce_targets(R, threshold, ramp, h, target, tau):
    """target[c] = C_R × approach where contact c bounces (else 0) and its time
    of impact τ as a fraction of the substep; returns how many bounce."""
    count = 0
    for c in range(len(R)):
        approach = -R[c, U0]
        target[c] = 0.0
        tau[c] = 1.0
        if not approach > threshold:
            continue
        e = effective_restitution(R[c, E], approach, threshold, ramp)
        if e > 0.0 and R[c, LAM] > 0.0:
            target[c] = e * approach
            s0 = approach * h - R[c, DEPTH]
            tau[c] = min(max(s0 / max(approach * h, 1e-300), 0.0), 1.0)
            count += 1
    return count
