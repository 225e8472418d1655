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
the summed update from overshooting. The Gauss–Seidel sweep ends with such
a batch too when its last colours are sparse (pipeline.merge_tail).

V is the (n, 6) C-ordered array of body (v, ω); a batch reads and writes
its bodies' 12 numbers through flat indices (take / put), the cheapest
gather and scatter numpy has. Rows carry their Jacobian pre-multiplied by the
effective masses (contact_rows.ContactRows.Js), so one product gives the
impulse each row asks for.
"""
import numpy as np

from . import friction

try:        # the C entry point of np.einsum, without the Python dispatch layer
    from numpy._core.multiarray import c_einsum as _einsum
except ImportError:     # pragma: no cover - other numpy layouts
    _einsum = np.einsum
einsum = _einsum


def _slices(rows):
    """(slice, summed) per batch: summed when its rows may share a body."""
    bd = rows.bounds
    return [(slice(int(bd[i]), int(bd[i + 1])), int(bd[i]) >= rows.summed_from)
            for i in range(len(bd) - 1)]


def flat_index(ab, width):
    """(k, 2·width) indices of the two bodies' `width` numbers in a flat (n·width,) array."""
    return (ab[:, :, None] * width + np.arange(width)).reshape(len(ab), 2 * width)


def flat6(rows):
    """rows' flat_index(ab, 6), made once per set of rows (warm start, solve, slip)."""
    if rows.flat6 is None:
        rows.flat6 = flat_index(rows.ab, 6)
    return rows.flat6


def _groups(rows, sel, summed):
    """The sorted row indices `sel` split by batch, each with its summed flag."""
    bd = rows.bounds
    cut = np.split(sel, np.searchsorted(sel, bd[1:-1]))
    return [(g, summed or int(bd[i]) >= rows.summed_from) for i, g in enumerate(cut) if len(g)]


def _scatter(Vf, idx, new, delta, summed):
    if summed:
        np.add.at(Vf, idx, delta)
    else:
        # a batch shares no moving body; a static or sleeping one may repeat,
        # and gets back its own (zero) velocity
        Vf[idx] = new


def tangential_slip(V, rows):
    """(k,) speed of sliding at each contact, |v_t|, with the velocities V."""
    u = _einsum("kri,ki->kr", rows.J[:, 1:, :], V.reshape(-1).take(flat6(rows)))
    return np.sqrt(_einsum("ij,ij->i", u, u))


def warm_start(V, rows, summed):
    """Apply the accumulated impulses λ the rows start with."""
    if not len(rows) or not rows.lam.any():
        return
    d = _einsum("kr,kri->ki", rows.lam, rows.M)
    Vf = V.reshape(-1)
    Vf += np.bincount(flat6(rows).reshape(-1), d.reshape(-1), len(Vf))


def solve_velocities(V, rows, iterations, summed, tolerance=0.0):
    """Normal (non-penetration, target rows.bias) and friction rows, at most
    `iterations` sweeps; stops after a sweep that changed no impulse by more
    than what moves a contact's relative velocity by `tolerance` (m/s).
    Returns the number of sweeps done."""
    Vf = V.reshape(-1)
    views = []
    idx6 = flat6(rows)
    for s, sum_s in _slices(rows):
        views.append((sum_s or summed, idx6[s], rows.Js[s], rows.M[s], rows.mass_bias[s],
                      rows.g_tn[s], rows.mu[s], rows.sliding[s], rows.lam[s], rows.wtt[s], rows.w_tn[s],
                      bool(np.count_nonzero(rows.sliding[s]))))
    # an impulse change dλ moves a row's relative velocity by about dλ / m_eff
    limit = tolerance * float(rows.mass_n.min()) if tolerance > 0.0 and len(rows) else -1.0
    check = limit > 0.0
    for sweep in range(iterations):
        change = 0.0     # largest impulse change of this sweep (each row is updated once)
        for sum_s, idx, Js, M, mass_bias, g_tn, mu, sliding, lam_s, wtt, w_tn, any_sliding in views:
            VAB = Vf.take(idx)
            us = _einsum("kri,ki->kr", Js, VAB)      # (m_n u_n, W_tt⁻¹ u_t)
            old = lam_s.copy()
            ln = np.maximum(old[:, 0] - us[:, 0] + mass_bias, 0.0)
            dn = ln - old[:, 0]
            # friction sees the velocity after this normal change (W_tn couples them)
            lt = old[:, 1:] - us[:, 1:] - g_tn * dn[:, None]
            lam_s[:, 0] = ln
            lam_s[:, 1:] = friction.cap(
                lt, ln, mu, sliding,
                lambda: (_einsum("kij,kj->ki", wtt, us[:, 1:]) + w_tn * dn[:, None]) if any_sliding else None)
            dl = lam_s - old
            d = _einsum("kr,kri->ki", dl, M)
            _scatter(Vf, idx, VAB + d, d, sum_s)
            if check:
                m = float(np.abs(dl).max())
                if not m < change:      # NaN propagates: no early stop
                    change = m
        if check and change < limit:
            return sweep + 1
    return iterations


def solve_normal_targets(V, rows, target, active, iterations, summed):
    """Normal rows only, driven to `target` (k,) where `active`: the restitution pass.

    λ keeps accumulating on top of the solve's, still clamped at ≥ 0, so a
    bounce only ever pushes (Box2D's restitution stage)."""
    idx_all = np.flatnonzero(active)
    if not len(idx_all):
        return
    groups = _groups(rows, idx_all, summed)
    Vf = V.reshape(-1)
    lam = rows.lam
    for _ in range(iterations):
        for g, sum_g in groups:
            idx = flat6(rows)[g]
            VAB = Vf.take(idx)
            un = _einsum("ki,ki->k", rows.J[g, 0, :], VAB)
            ln_old = lam[g, 0]
            ln = np.maximum(ln_old - rows.mass_n[g] * (un - target[g]), 0.0)
            lam[g, 0] = ln
            d = (ln - ln_old)[:, None] * rows.M[g, 0, :]
            _scatter(Vf, idx, VAB + d, d, sum_g)


def solve_pseudo(Xp, rows, target, iterations, summed):
    """Pseudo-velocities (split impulse): normal rows pushed apart to `target`,
    starting from zero. They move positions and are then thrown away, so
    pushing bodies apart adds no kinetic energy. Only translation: a push-out
    that also turned the bodies would tilt a box out of the floor (and lift it)
    whenever the sweep order makes one corner's push larger than another's.
    Xp (n, 3) is the pseudo-velocity of the centres.

    Only rows of bodies that some row must push take part (with every other
    row of those bodies, so a push does not drive them into a neighbour)."""
    push = target > 0.0
    bodies = np.zeros(len(Xp), bool)
    bodies[rows.a[push]] = True
    bodies[rows.b[push]] = True
    sel = np.flatnonzero(bodies[rows.a] | bodies[rows.b])
    groups = _groups(rows, sel, summed)
    n = rows.normal
    ima = -_einsum("ki,ki->k", rows.M[:, 0, 0:3], n)     # 1/m_a (0 static or asleep)
    imb = _einsum("ki,ki->k", rows.M[:, 0, 6:9], n)
    mass = 1.0 / np.maximum(ima * rows.split[:, 0] + imb * rows.split[:, 1], 1e-300)
    # per row: the pseudo-velocity change of (a, b) per unit push, and the
    # normal as a (6,) row giving n·(x_b − x_a)
    step = np.concatenate([-ima[:, None] * n, imb[:, None] * n], axis=1)
    jn = np.concatenate([-n, n], axis=1)
    Xf = Xp.reshape(-1)
    views = [(flat_index(rows.ab[g], 3), jn[g], step[g], mass[g], target[g], sum_g)
             for g, sum_g in groups]
    lam = [np.zeros(len(g)) for g, _ in groups]
    for _ in range(iterations):
        for (idx, j, st, m, tg, sum_g), l_old in zip(views, lam):
            XAB = Xf.take(idx)
            un = _einsum("ki,ki->k", j, XAB)
            l_new = np.maximum(l_old - m * (un - tg), 0.0)
            d = (l_new - l_old)[:, None] * st
            l_old[:] = l_new
            _scatter(Xf, idx, XAB + d, d, sum_g)
