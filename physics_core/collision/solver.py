"""Projected Gauss–Seidel over contact rows, one graph colour at a time (COURSE.md 5).

Sequential impulses (Box2D): each contact keeps its accumulated impulse λ;
an update computes the change that would bring the row's relative velocity
to its target, adds it to λ, clamps λ (normal ≥ 0; tangential inside the
friction cap of friction.py) and applies only the clamped change. The
accumulated, clamped λ is what makes many simultaneous contacts converge
and lets last step's λ be applied first (warm starting).

A batch is a slice of rows sharing no moving body (coloring.py), so its
update is a handful of numpy operations and the writes back to the body
velocities never collide. In `jacobi` mode there is one batch holding every
row; a body's rows then read the same velocities and their changes are
summed, and each body's inverse mass in the effective masses was multiplied
by its number of contacts (mass splitting, Tonge et al. 2012), which keeps
the summed update from overshooting.

V is the (n, 6) array of body (v, ω); only rows in the batch are touched.
"""
import numpy as np

from . import friction


def _gather(V, rows, s):
    """(k, 12) velocities of the two bodies of rows s, and the row velocities (k, 3)."""
    ab = rows.ab[s]
    VAB = V[ab].reshape(len(ab), 12)
    return ab, VAB, np.einsum("kri,ki->kr", rows.J[s], VAB)


def _apply(V, rows, s, P, ab, VAB, summed):
    """Add M⁻¹Jᵀ P to the two bodies of rows s."""
    d = np.einsum("kr,kri->ki", P, rows.M[s])
    if summed:
        np.add.at(V, ab.reshape(-1), d.reshape(-1, 6))
    else:
        # a batch shares no moving body; a static or sleeping one may repeat,
        # and gets back its own (zero) velocity
        V[ab] = (VAB + d).reshape(-1, 2, 6)


def _slices(rows):
    bd = rows.bounds
    return [slice(int(bd[i]), int(bd[i + 1])) for i in range(len(bd) - 1)]


def tangential_slip(V, rows):
    """(k,) speed of sliding at each contact, |v_t|, with the velocities V."""
    u = np.einsum("kri,ki->kr", rows.J[:, 1:, :], V[rows.ab].reshape(len(rows), 12))
    return np.sqrt(np.einsum("ij,ij->i", u, u))


def warm_start(V, rows, summed):
    """Apply the accumulated impulses λ the rows start with."""
    if not len(rows) or not rows.lam.any():
        return
    d = np.einsum("kr,kri->ki", rows.lam, rows.M)
    np.add.at(V, rows.ab.reshape(-1), d.reshape(-1, 6))


def solve_velocities(V, rows, iterations, summed, tolerance=0.0):
    """Normal (non-penetration, target rows.bias) and friction rows, at most
    `iterations` sweeps; stops after a sweep in which no impulse change moved
    a contact's relative velocity by more than `tolerance` (m/s).
    Returns the number of sweeps done."""
    slices = _slices(rows)
    lam = rows.lam
    w_nn = 1.0 / rows.mass_n
    for sweep in range(iterations):
        change = 0.0
        for s in slices:
            ab, VAB, u = _gather(V, rows, s)
            ln_old = lam[s, 0]
            ln = np.maximum(ln_old - rows.mass_n[s] * (u[:, 0] - rows.bias[s]), 0.0)
            P = np.empty((len(ln), 3))
            P[:, 0] = ln - ln_old
            # friction sees the velocity after this normal change (W_tn couples them)
            ut = u[:, 1:] + rows.w_tn[s] * P[:, :1]
            lt_old = lam[s, 1:]
            lt = lt_old - np.einsum("kij,kj->ki", rows.wtt_inv[s], ut)
            lt = friction.cap(lt, ln, rows.mu[s], rows.sliding[s], ut)
            P[:, 1:] = lt - lt_old
            lam[s, 0] = ln
            lam[s, 1:] = lt
            _apply(V, rows, s, P, ab, VAB, summed)
            if tolerance > 0.0:
                change = max(change, float((np.abs(P).max(axis=1) * w_nn[s]).max()))
        if change < tolerance:
            return sweep + 1
    return iterations


def solve_normal_targets(V, rows, target, active, iterations, summed):
    """Normal rows only, driven to `target` (k,) where `active`: the restitution pass.

    λ keeps accumulating on top of the solve's, still clamped at ≥ 0, so a
    bounce only ever pushes (Box2D's restitution stage)."""
    idx_all = np.flatnonzero(active)
    if not len(idx_all):
        return
    bd = rows.bounds
    groups = np.split(idx_all, np.searchsorted(idx_all, bd[1:-1]))
    groups = [g for g in groups if len(g)]
    lam = rows.lam
    for _ in range(iterations):
        for g in groups:
            ab, VAB, u = _gather(V, rows, g)
            ln_old = lam[g, 0]
            ln = np.maximum(ln_old - rows.mass_n[g] * (u[:, 0] - target[g]), 0.0)
            P = np.zeros((len(g), 3))
            P[:, 0] = ln - ln_old
            lam[g, 0] = ln
            _apply(V, rows, g, P, ab, VAB, summed)


def solve_pseudo(Xp, rows, target, iterations, summed):
    """Pseudo-velocities (split impulse): normal rows pushed apart to `target`,
    starting from zero. They move positions and are then thrown away, so
    pushing bodies apart adds no kinetic energy. Only translation: a push-out
    that also turned the bodies would tilt a box out of the floor (and lift it)
    whenever the sweep order makes one corner's push larger than another's.
    Xp (n, 3) is the pseudo-velocity of the centres."""
    slices = _slices(rows)
    lam = np.zeros(len(rows))
    n = rows.normal
    ima = -np.einsum("ki,ki->k", rows.M[:, 0, 0:3], n)     # 1/m_a (0 static or asleep)
    imb = np.einsum("ki,ki->k", rows.M[:, 0, 6:9], n)
    mass = 1.0 / np.maximum(ima * rows.split[:, 0] + imb * rows.split[:, 1], 1e-300)
    for _ in range(iterations):
        for s in slices:
            ab = rows.ab[s]
            XAB = Xp[ab]                                       # (k, 2, 3)
            un = np.einsum("ki,ki->k", XAB[:, 1] - XAB[:, 0], n[s])
            l_old = lam[s]
            l_new = np.maximum(l_old - mass[s] * (un - target[s]), 0.0)
            d = (l_new - l_old)[:, None] * n[s]
            lam[s] = l_new
            step = np.stack([-ima[s, None] * d, imb[s, None] * d], axis=1)
            if summed:
                np.add.at(Xp, ab.reshape(-1), step.reshape(-1, 3))
            else:
                Xp[ab] = XAB + step
