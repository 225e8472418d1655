"""The correct stage, compiled: positions follow the solved velocities, and
overlap beyond `slop` is pushed out by pseudo-velocities (split impulse).

The integrator moved every body with its unconstrained velocity u0; the
solve changed it to v, so the body is moved on by (v − u0) h, the pose the
integrator would have given with v (COURSE.md 4). A bounce acts from its
time of impact τ h on (bounce.py): the change then counts for the rest of
the substep only, (1 − τ) h. A body the ccd stage moved back to its time of
impact t moves from there with its solved velocity for the rest, (1 − t) h.
Friction at its kinetic bound is a constant force over the substep: the part
of the change it made moves the body by half as much (kinetic_drift.py).

What overlap is left beyond `slop` is removed at `correction_rate` per
substep, at most `max_correction_speed`, by pseudo-velocities that move
positions and are then thrown away, so pushing bodies apart adds no kinetic
energy. Only translation: a push-out that also turned the bodies would tilt
a box out of the floor whenever one corner's push is larger than another's.
"""
from numba import njit

from ..quaternion import integrate_one, row4
from .contact_layout import (ARM_A, ARM_B, BODY_A, BODY_B, DEPTH, DIR, INV_MASS_A, INV_MASS_B)
from .scratch import take, take_bools, take_rows


@njit(cache=True, inline="always")
def bounce_remainders(I, target, tau, after):
    """after (n,): per body the largest 1 − τ of its bouncing contacts (-1: none)."""
    after[:] = -1.0
    for c in range(len(target)):
        if target[c] > 0.0:
            for body in (I[c, BODY_A], I[c, BODY_B]):
                after[body] = max(after[body], 1.0 - tau[c])
    return after


@njit(cache=True, inline="always")
def velocity_changes(vel, omega, vel0, omega0, I, target, tau, toi, slide, store):
    """(n, 6) the rate each body still moves at over h beyond the integrator's
    motion: what the solve changed, over the part of the substep it acts on;
    a body moved back to its time of impact toi (≥ 0) moves with its solved
    velocity over the rest of the substep, (1 − toi) h. slide (n, 3) or
    (0, 3): the part of the change made by friction at its kinetic bound, a
    constant force over the substep, which moves the body by half of it
    (kinetic_drift.py)."""
    n = len(vel)
    after = bounce_remainders(I, target, tau, take(store, n))
    half = len(slide) == n
    dV = take_rows(store, n, 6)
    for i in range(n):
        rest = 1.0 - toi[i]
        scale = after[i] if after[i] >= 0.0 else 1.0
        drift = half and toi[i] < 0.0 and after[i] < 0.0
        for j in range(3):
            if toi[i] >= 0.0:
                dV[i, j], dV[i, 3 + j] = vel[i, j] * rest, omega[i, j] * rest
            else:
                dV[i, j] = (vel[i, j] - vel0[i, j]) * scale - (0.5 * slide[i, j] if drift else 0.0)
                dV[i, 3 + j] = (omega[i, j] - omega0[i, j]) * scale
    return dV


@njit(cache=True, inline="always")
def separations(R, I, dV, h, out):
    """Separation of each contact after moving by dV h: n·Δ(x_b − x_a) − depth."""
    for c in range(len(R)):
        a, b = I[c, BODY_A], I[c, BODY_B]
        s = 0.0
        for i in range(3):
            s += (R[c, DIR + i] * (dV[b, i] - dV[a, i])
                  + R[c, ARM_B + i] * dV[b, 3 + i] - R[c, ARM_A + i] * dV[a, 3 + i])
        out[c] = s * h - R[c, DEPTH]


@njit(cache=True, inline="always")
def push_targets(sep, slop, rate, max_speed, h, target):
    """Pseudo-velocity each contact asks for; returns how many ask."""
    count = 0
    for c in range(len(sep)):
        target[c] = 0.0
        if sep[c] < -slop:
            target[c] = max(min(rate * (-sep[c] - slop) / h, max_speed), 0.0)
            if target[c] > 0.0:
                count += 1
    return count


@njit(cache=True, inline="always")
def solve_pseudo(R, I, target, iterations, n, store):
    """(n, 3) pseudo-velocities of the centres: normal rows pushed apart to
    `target`, from zero. Only rows of bodies that some row must push take
    part (with every other row of those bodies, so a push does not drive
    them into a neighbour). Its arrays are views of the substep's scratch
    (scratch.py), not allocations."""
    pushed = take_bools(store, n)
    pushed[:] = False
    for c in range(len(R)):
        if target[c] > 0.0:
            pushed[I[c, BODY_A]] = True
            pushed[I[c, BODY_B]] = True
    X = take_rows(store, n, 3)
    X[:] = 0.0
    lam = take(store, len(R))
    lam[:] = 0.0
    for _ in range(iterations):
        for c in range(len(R)):
            a, b = I[c, BODY_A], I[c, BODY_B]
            if not (pushed[a] or pushed[b]):
                continue
            ima, imb = R[c, INV_MASS_A], R[c, INV_MASS_B]
            un = 0.0
            for i in range(3):
                un += R[c, DIR + i] * (X[b, i] - X[a, i])
            new = max(lam[c] - (un - target[c]) / max(ima + imb, 1e-300), 0.0)
            d = new - lam[c]
            lam[c] = new
            for i in range(3):
                X[a, i] -= ima * R[c, DIR + i] * d
                X[b, i] += imb * R[c, DIR + i] * d
    return X


@njit(cache=True, inline="always")
def move_bodies(pos, quat, dV, X, h):
    """x += (Δv + pseudo-velocity) h; q turned by Δω h where Δω ≠ 0."""
    for i in range(len(pos)):
        for j in range(3):
            pos[i, j] += (dV[i, j] + X[i, j]) * h if X.shape[0] else dV[i, j] * h
        if dV[i, 3] != 0.0 or dV[i, 4] != 0.0 or dV[i, 5] != 0.0:
            q = integrate_one(row4(quat, i), (dV[i, 3], dV[i, 4], dV[i, 5]), h)
            quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3] = q


@njit(cache=True, inline="always")
def correct(R, I, pos, quat, vel, omega, vel0, omega0, target, tau, toi, slide, h, slop, rate,
            max_speed, iterations, store):
    """The whole correct stage (see the module docstring); store: the
    substep's scratch (scratch.py)."""
    dV = velocity_changes(vel, omega, vel0, omega0, I, target, tau, toi, slide, store)
    k = len(R)
    sep = take(store, k)
    separations(R, I, dV, h, sep)
    push = take(store, k)
    X = take_rows(store, 0, 3)
    if iterations > 0 and rate > 0.0 and max_speed > 0.0 and push_targets(sep, slop, rate,
                                                                            max_speed, h, push):
        X = solve_pseudo(R, I, push, iterations, len(pos), store)
    move_bodies(pos, quat, dV, X, h)
