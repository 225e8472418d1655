"""The per-body update loops of the four integrators (COURSE.md 3 and 4),
called between force evaluations by integration.integrate_substep.

State y = (x, q, v, L): position, orientation, velocity and world angular
momentum L = I_w ω with I_w = R diag(I) Rᵀ. Working with L makes the
gyroscopic term exact: with no torque L stays constant whatever the
integrator, and ω = I_w⁻¹ L follows the orientation, which gives the
intermediate-axis flip of an asymmetric body (COURSE.md 3). Orientation is
advanced by the exact exponential map of ω h, so it stays a unit quaternion;
semi-implicit Euler and velocity Verlet advance it by the torque-free
splitting of free_rotation.py between torque kicks, so that, like their
translational update, they keep the energy of a free body bounded.

Each loop runs over every body once (Numba, float64, no fast-math, serial,
so every run gives the same bits) and updates the state in place. With
`rotating` false (no body spins and nothing can apply torque) the rotational
half is skipped. `iso` flags the isotropic bodies: for them I_w = I 1, so
L = I ω and ω = L / I need no change of frame, and their orientation follows
the exact map. `inv_mass` is (n,) and `inv_inertia` (n, 3), zero for static
and sleeping bodies; the scratch arrays are preallocated by the caller
(integration.integration_work).
"""
from numba import njit

from .free_rotation import advance_one, diagonal_one, turn_one
from .quaternion import derivative_one, normalize_one, row3, row4


# ---- one body's pieces --------------------------------------------------------

@njit(cache=True, inline="always")
def _set3(a, i, v):
    a[i, 0], a[i, 1], a[i, 2] = v


@njit(cache=True, inline="always")
def _set4(a, i, v):
    a[i, 0], a[i, 1], a[i, 2], a[i, 3] = v


@njit(cache=True, inline="always")
def _momentum_plus(quat, omega, inertia, iso, i, T, c):
    """L = I_w ω + c τ for body i (the torque kick of length c)."""
    L = diagonal_one(row4(quat, i), row3(inertia, i), row3(omega, i), iso[i])
    return (L[0] + T[i, 0] * c, L[1] + T[i, 1] * c, L[2] + T[i, 2] * c)


@njit(cache=True, inline="always")
def _plus(a, b, c):
    """a + c b for two 3-tuples."""
    return (a[0] + c * b[0], a[1] + c * b[1], a[2] + c * b[2])


# ---- explicit and semi-implicit Euler ---------------------------------------------

@njit(cache=True)
def explicit_euler_update(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating):
    """x ← x + v h, v ← v + a h; L ← I_w ω + τ h, q turned by the start-of-step ω."""
    for i in range(len(pos)):
        im = inv_mass[i]
        for k in range(3):
            pos[i, k] += vel[i, k] * h
            vel[i, k] += F[i, k] * im * h
        if rotating:
            L = _momentum_plus(quat, omega, inertia, iso, i, T, h)
            q = turn_one(row4(quat, i), row3(omega, i), h)
            _set4(quat, i, q)
            _set3(omega, i, diagonal_one(q, row3(inv_inertia, i), L, iso[i]))


@njit(cache=True, inline="always")
def semi_implicit_update(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating):
    """v ← v + a h, x ← x + v h (symplectic Euler); L ← I_w ω + τ h, then the
    torque-free rotation."""
    for i in range(len(pos)):
        im = inv_mass[i]
        for k in range(3):
            vel[i, k] += F[i, k] * im * h
            pos[i, k] += vel[i, k] * h
        if rotating:
            L = _momentum_plus(quat, omega, inertia, iso, i, T, h)
            q, w = advance_one(row4(quat, i), L, row3(inv_inertia, i), h, iso[i])
            _set4(quat, i, q)
            _set3(omega, i, w)


# ---- velocity Verlet ------------------------------------------------------------

@njit(cache=True)
def verlet_drift(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating, work):
    """Kick ½h and drift h. Leaves in `work` (4, n, 3): v_half, the predicted end
    velocity v_half + ½h a, L_half and the predicted end ω = I_w⁻¹ (L_half + ½h τ)
    (the last two only when rotating)."""
    half = 0.5 * h
    v_half, v_pred, L_half, omega_pred = work[0], work[1], work[2], work[3]
    for i in range(len(pos)):
        im = inv_mass[i]
        for k in range(3):
            a = F[i, k] * im
            v_half[i, k] = vel[i, k] + half * a
            pos[i, k] += v_half[i, k] * h
            v_pred[i, k] = v_half[i, k] + half * a
        if rotating:
            L = _momentum_plus(quat, omega, inertia, iso, i, T, half)
            inv = row3(inv_inertia, i)
            q, _ = advance_one(row4(quat, i), L, inv, h, iso[i])
            _set4(quat, i, q)
            _set3(L_half, i, L)
            _set3(omega_pred, i, diagonal_one(q, inv, _plus(L, row3(T, i), half), iso[i]))


@njit(cache=True)
def verlet_kick(quat, vel, omega, F, T, inv_mass, inv_inertia, iso, h, rotating, work):
    """The closing ½h kick with the end-point forces."""
    half = 0.5 * h
    v_half, L_half = work[0], work[2]
    for i in range(len(vel)):
        im = inv_mass[i]
        for k in range(3):
            vel[i, k] = v_half[i, k] + half * F[i, k] * im
        if rotating:
            L = _plus(row3(L_half, i), row3(T, i), half)
            _set3(omega, i, diagonal_one(row4(quat, i), row3(inv_inertia, i), L, iso[i]))


# ---- RK4 ---------------------------------------------------------------------------
# y0 = (x, v, q, L) at the start of the step, one row of 13 numbers per body (only
# the first 6, x and v, are used when nothing turns), and `total` = k₁ + 2 k₂ + 2 k₃
# of the slopes k = (v, a, dq/dt, τ) in the same layout. The per-body helpers take
# and return tuples, or are too small not to be inlined: an array passed to a call
# that is not inlined costs reference counting on every body.
_X, _V, _Q, _L = 0, 3, 6, 10
WIDTH = 13


@njit(cache=True, inline="always")
def _stage_turn(y_q, y_L, inv, iso):
    """A stage's orientation normalised, and ω = I_w⁻¹ L at it."""
    q = normalize_one(y_q)
    return q, diagonal_one(q, inv, y_L, iso)


@njit(cache=True, inline="always")
def _add_slope(total, i, j, k, first):
    """total = k₁, then total + 2 k for the next two stages."""
    total[i, j] = k if first else total[i, j] + 2.0 * k


@njit(cache=True, inline="always")
def _ahead3(y0, i, col, c, k):
    """y0 + c k for 3 numbers from column col of body i."""
    return (y0[i, col] + c * k[0], y0[i, col + 1] + c * k[1], y0[i, col + 2] + c * k[2])


@njit(cache=True, inline="always")
def _ahead4(y0, i, col, c, k):
    return (y0[i, col] + c * k[0], y0[i, col + 1] + c * k[1], y0[i, col + 2] + c * k[2],
            y0[i, col + 3] + c * k[3])


@njit(cache=True, inline="always")
def _with_total3(total, i, col, k):
    """total + k for 3 numbers (the final k₁ + 2 k₂ + 2 k₃ + k₄)."""
    return (total[i, col] + k[0], total[i, col + 1] + k[1], total[i, col + 2] + k[2])


@njit(cache=True, inline="always")
def _with_total4(total, i, col, k):
    return (total[i, col] + k[0], total[i, col + 1] + k[1], total[i, col + 2] + k[2],
            total[i, col + 3] + k[3])


@njit(cache=True)
def rk4_begin(rotating, pos, quat, vel, omega, inertia, inv_inertia, iso, y0, x, q, v, w):
    """y0 = (x, v[, q, L = I_w ω]) from the state, and the first stage's pose
    (q, w are written only when rotating; otherwise they are the state's own)."""
    for i in range(len(pos)):
        for k in range(3):
            y0[i, _X + k] = x[i, k] = pos[i, k]
            y0[i, _V + k] = v[i, k] = vel[i, k]
        if rotating:
            q_i = row4(quat, i)
            L = diagonal_one(q_i, row3(inertia, i), row3(omega, i), iso[i])
            for k in range(4):
                y0[i, _Q + k] = q_i[k]
            for k in range(3):
                y0[i, _L + k] = L[k]
            q_n, w_n = _stage_turn(q_i, L, row3(inv_inertia, i), iso[i])
            _set4(q, i, q_n)
            _set3(w, i, w_n)


@njit(cache=True)
def rk4_stage(rotating, y0, total, first, c, x, q, v, w, F, T, inv_mass, inv_inertia, iso):
    """This stage's slope k (at the pose in x, q, v, w) into `total`, and the next
    stage's pose y0 + c k written over this one (rows are independent)."""
    for i in range(len(x)):
        im = inv_mass[i]
        for k in range(3):
            kx, kv = v[i, k], F[i, k] * im
            _add_slope(total, i, _X + k, kx, first)
            _add_slope(total, i, _V + k, kv, first)
            x[i, k] = y0[i, _X + k] + c * kx
            v[i, k] = y0[i, _V + k] + c * kv
        if rotating:
            kq, kL = derivative_one(row4(q, i), row3(w, i)), row3(T, i)
            for k in range(4):
                _add_slope(total, i, _Q + k, kq[k], first)
            for k in range(3):
                _add_slope(total, i, _L + k, kL[k], first)
            q_i, w_i = _stage_turn(_ahead4(y0, i, _Q, c, kq), _ahead3(y0, i, _L, c, kL),
                                   row3(inv_inertia, i), iso[i])
            _set4(q, i, q_i)
            _set3(w, i, w_i)


@njit(cache=True)
def rk4_finish(rotating, y0, total, weight, x, q, v, w, F, T, inv_mass, inv_inertia, iso,
               pos, quat, vel, omega):
    """y = y0 + (h/6)(k₁ + 2 k₂ + 2 k₃ + k₄) into the state; ω = I_w⁻¹ L at the new q."""
    for i in range(len(x)):
        im = inv_mass[i]
        for k in range(3):
            kx, kv = v[i, k], F[i, k] * im
            pos[i, k] = y0[i, _X + k] + weight * (total[i, _X + k] + kx)
            vel[i, k] = y0[i, _V + k] + weight * (total[i, _V + k] + kv)
        if rotating:
            kq = _with_total4(total, i, _Q, derivative_one(row4(q, i), row3(w, i)))
            kL = _with_total3(total, i, _L, row3(T, i))
            q_i, w_i = _stage_turn(_ahead4(y0, i, _Q, weight, kq), _ahead3(y0, i, _L, weight, kL),
                                   row3(inv_inertia, i), iso[i])
            _set4(quat, i, q_i)
            _set3(omega, i, w_i)
