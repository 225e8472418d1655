"""Per-body loops of the embedded Runge–Kutta step (adaptive.py drives them).

State y = (x, v, q, L) as in RK4 (integrator_kernels.py): one row of 13 per
body in `y0` (only x, v when nothing turns), slopes K[j] = (v, a, dq/dt, τ)
in the same layout. A stage's orientation is normalised before ω = I_w⁻¹ L
is taken at it; the committed orientation is normalised too, so it stays a
unit quaternion. Sums over stages run in stage order (no fast-math), so the
same inputs give the same bits.

The error norm (step_error) is per body and per quantity, each in its own
unit: |Δx| (m), |Δv| (m/s), |Δq| (the unit quaternion's change, ≈ half the
angle, rad) and |ΔL| × max(1/I) (a bound on |Δω|, rad/s), each divided by
atol + rtol × (the larger of its size at the step's start and end); the
body's error is the largest of these, the step's the largest over bodies
(Hairer, Nørsett & Wanner I, II.4, with the max norm over bodies so that a
light body beside a heavy one is held to the same tolerance).
"""
import math

from numba import njit

from .free_rotation import diagonal_one
from .quaternion import derivative_one, normalize_one, row3, row4

_X, _V, _Q, _L = 0, 3, 6, 10
RTOL, ATOL_X, ATOL_V, ATOL_Q, ATOL_W = range(5)   # tol[...] slots


@njit(cache=True)
def load_start(rotating, pos, quat, vel, omega, inertia, iso, y0):
    """y0 = (x, v[, q, L = I_w ω]) from the state."""
    for i in range(len(pos)):
        for k in range(3):
            y0[i, _X + k] = pos[i, k]
            y0[i, _V + k] = vel[i, k]
        if rotating:
            q = row4(quat, i)
            L = diagonal_one(q, row3(inertia, i), row3(omega, i), iso[i])
            for k in range(4):
                y0[i, _Q + k] = q[k]
            for k in range(3):
                y0[i, _L + k] = L[k]


@njit(cache=True)
def _combine(y0, K, coef, h, i, col):
    """y0[i, col] + h Σ_j coef[j] K[j, i, col], j in stage order."""
    s = 0.0
    for j in range(len(coef)):
        if coef[j] != 0.0:
            s += coef[j] * K[j, i, col]
    return y0[i, col] + h * s


@njit(cache=True)
def _ahead(y0, K, coef, h, i, col, width):
    if width == 3:
        return (_combine(y0, K, coef, h, i, col), _combine(y0, K, coef, h, i, col + 1),
                _combine(y0, K, coef, h, i, col + 2), 0.0)
    return (_combine(y0, K, coef, h, i, col), _combine(y0, K, coef, h, i, col + 1),
            _combine(y0, K, coef, h, i, col + 2), _combine(y0, K, coef, h, i, col + 3))


@njit(cache=True)
def stage_pose(rotating, y0, K, coef, h, x, q, v, w, inv_inertia, iso):
    """The pose y0 + h Σ coef[j] K[j] into x, v (and q normalised, ω at it)."""
    for i in range(len(x)):
        for k in range(3):
            x[i, k] = _combine(y0, K, coef, h, i, _X + k)
            v[i, k] = _combine(y0, K, coef, h, i, _V + k)
        if rotating:
            qn = normalize_one(_ahead(y0, K, coef, h, i, _Q, 4))
            L = _ahead(y0, K, coef, h, i, _L, 3)
            wn = diagonal_one(qn, row3(inv_inertia, i), (L[0], L[1], L[2]), iso[i])
            q[i, 0], q[i, 1], q[i, 2], q[i, 3] = qn
            w[i, 0], w[i, 1], w[i, 2] = wn


@njit(cache=True)
def stage_slope(rotating, K, j, q, v, w, F, T, inv_mass):
    """K[j] = (v, F / m[, dq/dt = ½ (0, ω) ⊗ q, τ]) at the stage's pose."""
    for i in range(len(v)):
        im = inv_mass[i]
        for k in range(3):
            K[j, i, _X + k] = v[i, k]
            K[j, i, _V + k] = F[i, k] * im
        if rotating:
            d = derivative_one(row4(q, i), row3(w, i))
            for k in range(4):
                K[j, i, _Q + k] = d[k]
            for k in range(3):
                K[j, i, _L + k] = T[i, k]


@njit(cache=True)
def _group(y0, K, b, e, h, ynew, i, col, width):
    """(|error estimate|, max(|y0|, |y_new|)) of one quantity of body i;
    y_new written into ynew."""
    d2 = a2 = n2 = 0.0
    for k in range(col, col + width):
        ynew[i, k] = _combine(y0, K, b, h, i, k)
        s = 0.0
        for j in range(len(e)):
            s += e[j] * K[j, i, k]
        d = h * s
        d2 += d * d
        a2 += y0[i, k] * y0[i, k]
        n2 += ynew[i, k] * ynew[i, k]
    return math.sqrt(d2), math.sqrt(max(a2, n2))


@njit(cache=True)
def _ratio(err, size, atol, rtol):
    return err / (atol + rtol * size)


@njit(cache=True)
def _body_error(rotating, y0, K, b, e, h, ynew, i, inv_inertia, tol):
    """Body i's scaled error: the largest of its four quantities' (module docstring)."""
    ex, sx = _group(y0, K, b, e, h, ynew, i, _X, 3)
    ev, sv = _group(y0, K, b, e, h, ynew, i, _V, 3)
    r = max(_ratio(ex, sx, tol[ATOL_X], tol[RTOL]), _ratio(ev, sv, tol[ATOL_V], tol[RTOL]))
    if rotating:
        eq, sq = _group(y0, K, b, e, h, ynew, i, _Q, 4)
        eL, sL = _group(y0, K, b, e, h, ynew, i, _L, 3)
        im = max(inv_inertia[i, 0], inv_inertia[i, 1], inv_inertia[i, 2])
        r = max(r, _ratio(eq, sq, tol[ATOL_Q], tol[RTOL]), _ratio(eL * im, sL * im, tol[ATOL_W], tol[RTOL]))
    if ex != ex or ev != ev:
        return math.nan
    return r


@njit(cache=True)
def step_error(rotating, y0, K, b, e, h, ynew, inv_inertia, tol):
    """ynew = y0 + h Σ b_j K[j]; the step's scaled error (NaN if any body's is)."""
    worst = 0.0
    for i in range(len(y0)):
        r = _body_error(rotating, y0, K, b, e, h, ynew, i, inv_inertia, tol)
        if r != r:
            worst = math.nan
        elif r > worst:
            worst = r
    return worst


@njit(cache=True)
def commit(rotating, ynew, pos, quat, vel, omega, inv_inertia, iso):
    """The accepted y_new into the state; q normalised and ω = I_w⁻¹ L at it."""
    for i in range(len(pos)):
        for k in range(3):
            pos[i, k] = ynew[i, _X + k]
            vel[i, k] = ynew[i, _V + k]
        if rotating:
            qn = normalize_one((ynew[i, _Q], ynew[i, _Q + 1], ynew[i, _Q + 2], ynew[i, _Q + 3]))
            L = (ynew[i, _L], ynew[i, _L + 1], ynew[i, _L + 2])
            wn = diagonal_one(qn, row3(inv_inertia, i), L, iso[i])
            quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3] = qn
            omega[i, 0], omega[i, 1], omega[i, 2] = wn


@njit(cache=True)
def carry_last_slope(K):
    """K[0] = K[s − 1]: the FSAL slope of the accepted step starts the next."""
    last = len(K) - 1
    for i in range(K.shape[1]):
        for k in range(K.shape[2]):
            K[0, i, k] = K[last, i, k]
