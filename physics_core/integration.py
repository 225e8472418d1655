"""The integrate stage as compiled code: one substep of any of the four
integrators, with every declared force effect, callable from nopython code
(COURSE.md 2 and 4).

Made once per model (in Python), these carry everything a substep needs;
`can_make_torque(model)` gives integrate_substep's `model_torque`:

`integration_data(model)` -> data, a tuple (read by `forces` and
`integrate_substep`; the constants each effects/*.constants computes, so the
Python `apply`s and this path run one kernel on the same numbers):

    data[FLAGS]        int64 (N_EFFECTS,)  1 where the effect is declared, in
                       EFFECT_NAMES order (gravity, gravitation, drag, buoyancy, springs)
    data[ISO]          bool (n,)           isotropic bodies (free_rotation.isotropic_rows)
    data[EFFECT_DATA + e]                  effect e's constants tuple:
      gravity      (weight (n, 3),)
      gravitation  (idx (g,), m (g,), G, eps2, acc (g, 3) scratch)
      drag         (kind, idx (d,), b, area, half_rho_cd (d,), box bool (d,), face (d, 3),
                    re_factor (d,), threshold)
      buoyancy     (spheres (s,), r, sphere_volume (s,), boxes (b,), half (b, 3),
                    offsets (b, cells³, 3), cells, cell_volume, box_volume (b,), up (3,),
                    surface, linear, angular, damped)
      springs      (body int64 (2, m), local, fixed (2, m, 3), turns bool (2,), K, l0, C (m,),
                    damped, f (m, 3) scratch, arm (2, m, 3) scratch)

    An undeclared effect holds its module's `unused()`: the same types with no
    rows, so every scene has one data type (one compilation) and an undeclared
    effect costs one skipped branch. Integer arrays are int64, reals float64,
    all C-contiguous and writable. The gravitation and springs scratch makes a
    data tuple serve one evaluation at a time (the step is serial).

`integration_work(n)` -> work, the integrators' scratch, so a substep
allocates nothing:

    work = (F (n, 3), T (n, 3), vec (4, n, 3), quat (n, 4), y (2, n, 13))
    vec: velocity Verlet's v_half, v_pred, L_half, ω_pred; RK4's stage x, v, ω
    quat: RK4's stage orientation; y: RK4's y0 and k₁ + 2 k₂ + 2 k₃

`prof` int64 (N_EFFECTS,) (integration_profile()): cycles (cycle_clock.cycles, times
cycle_clock.seconds_per_cycle() for seconds) spent in each effect, added to;
an empty array turns the timing off.

Integrator codes: INTEGRATOR_CODES maps the scene names to EXPLICIT_EULER,
SEMI_IMPLICIT_EULER, VELOCITY_VERLET and RK4 (0..3).
"""
import numpy as np
from numba import njit

from .cycle_clock import cycles
from .effects import MODULES, ORDER, buoyancy, declared_effects, drag, gravitation, gravity, springs
from .effects.springs import makes_torque
from .free_rotation import isotropic_rows
from .integrator_kernels import (WIDTH, explicit_euler_update, rk4_begin, rk4_finish, rk4_stage,
                                 semi_implicit_update, verlet_drift, verlet_kick)
from .quaternion import cross_one, rotate_one, row3, row4
from .shapes import BOX

EXPLICIT_EULER, SEMI_IMPLICIT_EULER, VELOCITY_VERLET, RK4 = range(4)
INTEGRATOR_CODES = {"explicit_euler": EXPLICIT_EULER, "semi_implicit_euler": SEMI_IMPLICIT_EULER,
                    "velocity_verlet": VELOCITY_VERLET, "rk4": RK4}
EFFECT_NAMES = ORDER
GRAVITY, GRAVITATION, DRAG, BUOYANCY, SPRINGS = range(5)
N_EFFECTS = len(EFFECT_NAMES)
FLAGS, ISO, EFFECT_DATA = 0, 1, 2


def integration_data(model, isotropic=None):
    """The data tuple of one model (layout in the module docstring); built once
    per model, in Python. `isotropic` overrides the isotropic-body mask
    (default free_rotation.isotropic_rows(model.inertia), as the World's)."""
    declared = declared_effects(model)
    flags = np.array([name in declared for name in EFFECT_NAMES], dtype=np.int64)
    iso = isotropic_rows(model.inertia) if isotropic is None else isotropic
    effects = tuple(MODULES[name].constants(model) if name in declared else MODULES[name].unused()
                    for name in EFFECT_NAMES)
    return (flags, np.array(iso, dtype=bool)) + effects


def can_make_torque(model) -> bool:
    """Whether a declared effect can turn a body (a spring off a centre of mass,
    buoyancy on a box): integrate_substep's `model_torque`, as World._build
    computes it (contacts change ω directly, not through forces)."""
    return bool(makes_torque(model) or ("buoyancy" in model.effects and np.any(model.shape_type == BOX)))


def integration_work(n):
    """The integrators' scratch for n bodies (layout in the module docstring)."""
    return (np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((4, n, 3)), np.zeros((n, 4)),
            np.zeros((2, n, WIDTH)))


def integration_profile():
    """A prof array for `forces` and `integrate_substep`: cycles per effect, zero."""
    return np.zeros(N_EFFECTS, dtype=np.int64)


# ---- forces -------------------------------------------------------------------------
# The helpers that carry `data` are inlined (inline="always"): Numba counts the
# references of every array a compiled function receives (~10 ns an array, and
# `data` holds 31), and cannot drop the counting in a function with branches and
# calls. As separate functions the four levels between integrate_substep and the
# effect kernels cost ~3 µs a substep on one body; inlined, ~0.7 µs.

@njit(cache=True, inline="always")
def _tick(prof):
    """The cycle counter, when timing (prof not empty)."""
    return cycles() if len(prof) else 0


@njit(cache=True, inline="always")
def _tock(prof, effect, t0):
    """Cycles since t0 added to prof[effect], when timing."""
    if len(prof):
        prof[effect] += cycles() - t0


@njit(cache=True, inline="always")
def _effects(data, pos, quat, vel, omega, F, T, prof):
    """Every declared effect added into F and T, in EFFECT_NAMES order, each timed;
    an undeclared one costs its skipped branch."""
    flags, _, grav, gravitation_c, drag_c, buoyancy_c, springs_c = data
    if flags[GRAVITY]:
        t = _tick(prof)
        gravity.add(grav, pos, quat, vel, omega, F, T)
        _tock(prof, GRAVITY, t)
    if flags[GRAVITATION]:
        t = _tick(prof)
        gravitation.add(gravitation_c, pos, quat, vel, omega, F, T)
        _tock(prof, GRAVITATION, t)
    if flags[DRAG]:
        t = _tick(prof)
        drag.add(drag_c, pos, quat, vel, omega, F, T)
        _tock(prof, DRAG, t)
    if flags[BUOYANCY]:
        t = _tick(prof)
        buoyancy.add(buoyancy_c, pos, quat, vel, omega, F, T)
        _tock(prof, BUOYANCY, t)
    if flags[SPRINGS]:
        t = _tick(prof)
        springs.add(springs_c, pos, quat, vel, omega, F, T)
        _tock(prof, SPRINGS, t)


@njit(cache=True, inline="always")
def _user_loads(quat, user_force, user_force_offset, user_torque, has_user_force, has_user_torque, F, T):
    """The held loads, as World.forces adds them: F += the held force; T += the
    held torque + r × F, r the force's body-frame offset turned to world axes."""
    if has_user_force:
        for i in range(len(F)):
            for k in range(3):
                F[i, k] += user_force[i, k]
    if has_user_torque:
        for i in range(len(T)):
            r = rotate_one(row4(quat, i), row3(user_force_offset, i))
            c = cross_one(r, row3(user_force, i))
            for k in range(3):
                T[i, k] += user_torque[i, k] + c[k]


@njit(cache=True, inline="always")
def _all_forces(data, pos, quat, vel, omega, user_force, user_force_offset, user_torque,
                has_user_force, has_user_torque, F, T, prof):
    """F, T = zeros, the declared effects, the held loads (World.forces' order)."""
    for i in range(len(F)):
        for k in range(3):
            F[i, k] = 0.0
            T[i, k] = 0.0
    _effects(data, pos, quat, vel, omega, F, T, prof)
    _user_loads(quat, user_force, user_force_offset, user_torque, has_user_force, has_user_torque, F, T)


@njit(cache=True)
def forces(data, pos, quat, vel, omega, user_force, user_force_offset, user_torque,
           has_user_force, has_user_torque, F, T, prof=None):
    """F, T (n, 3) = the net force and torque (world frame) at a trial state, as
    World.forces computes them (COURSE.md 2): zeros, every declared effect in
    EFFECT_NAMES order, then the held force and torque. `prof` (optional,
    int64 (N_EFFECTS,)) gets each effect's cycles added."""
    if prof is None:
        _all_forces(data, pos, quat, vel, omega, user_force, user_force_offset, user_torque,
                    has_user_force, has_user_torque, F, T, np.zeros(0, dtype=np.int64))
    else:
        _all_forces(data, pos, quat, vel, omega, user_force, user_force_offset, user_torque,
                    has_user_force, has_user_torque, F, T, prof)


@njit(cache=True, inline="always")
def forces_at(data, loads, pos, quat, vel, omega, F, T, prof):
    """`forces` with the held loads as one tuple (user_force, offset, torque, has_force, has_torque)."""
    _all_forces(data, pos, quat, vel, omega, loads[0], loads[1], loads[2], loads[3], loads[4], F, T, prof)


# ---- the four integrators --------------------------------------------------------------
# state = (pos, quat, vel, omega), updated in place; body = (inv_mass, inertia,
# inv_inertia, iso); the update loops are integrator_kernels'.

@njit(cache=True, inline="always")
def _euler(semi, h, data, state, body, loads, rotating, work, prof):
    """Explicit or semi-implicit Euler: one force evaluation, one update loop."""
    pos, quat, vel, omega = state
    inv_mass, inertia, inv_inertia, iso = body
    F, T = work[0], work[1]
    forces_at(data, loads, pos, quat, vel, omega, F, T, prof)
    if semi:
        semi_implicit_update(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating)
    else:
        explicit_euler_update(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating)


@njit(cache=True, inline="always")
def _verlet(h, data, state, body, loads, rotating, work, prof):
    """Kick ½h, drift h, kick ½h with the forces at the new positions;
    velocity-dependent forces (drag, dampers) at the end point see the
    predicted velocity v + a h (and ω of L + h τ when rotating)."""
    pos, quat, vel, omega = state
    inv_mass, inertia, inv_inertia, iso = body
    F, T, vec = work[0], work[1], work[2]
    for end in range(2):                     # one call site: the forces are inlined once, not twice
        v_at = vec[1] if end else vel
        w_at = vec[3] if end and rotating else omega
        forces_at(data, loads, pos, quat, v_at, w_at, F, T, prof)
        if end:
            verlet_kick(quat, vel, omega, F, T, inv_mass, inv_inertia, iso, h, rotating, vec)
        else:
            verlet_drift(pos, quat, vel, omega, F, T, inv_mass, inertia, inv_inertia, iso, h, rotating, vec)


@njit(cache=True, inline="always")
def _rk4(h, data, state, body, loads, rotating, work, prof):
    """Classical fourth-order Runge–Kutta on (x, q, v, L); forces at each stage."""
    pos, quat, vel, omega = state
    inv_mass, inertia, inv_inertia, iso = body
    F, T, vec, stage_quat, y = work
    x, v = vec[0], vec[1]
    q, w = (stage_quat, vec[2]) if rotating else (quat, omega)
    y0, total = y[0], y[1]
    rk4_begin(rotating, pos, quat, vel, omega, inertia, inv_inertia, iso, y0, x, q, v, w)
    for stage in range(4):                   # one call site, as in _verlet
        forces_at(data, loads, x, q, v, w, F, T, prof)
        if stage < 3:
            rk4_stage(rotating, y0, total, stage == 0, h if stage == 2 else 0.5 * h, x, q, v, w, F, T,
                      inv_mass, inv_inertia, iso)
        else:
            rk4_finish(rotating, y0, total, h / 6.0, x, q, v, w, F, T, inv_mass, inv_inertia, iso,
                       pos, quat, vel, omega)


@njit(cache=True, inline="always")
def spins(omega):
    """Whether some body has ω ≠ 0 (NaN counts, as in numpy's any)."""
    for i in range(len(omega)):
        for k in range(3):
            if omega[i, k] != 0.0:
                return True
    return False


# Inlined in the step loop (step_loop._integrate): a call passed the data
# tuple's arrays (every effect's constants) field by field once per substep
@njit(cache=True, inline="always")
def integrate_substep(code, h, data, pos, quat, vel, omega, inv_mass, inertia, inv_inertia,
                      user_force, user_force_offset, user_torque, has_user_force, has_user_torque,
                      model_torque, work, prof):
    """One substep of length h of integrator `code` (INTEGRATOR_CODES), state
    arrays updated in place (COURSE.md 4). The rotational half runs when the
    World would: some effect can make torque (model_torque), a torque is held,
    or some body spins. inv_mass (n,) and inv_inertia (n, 3) are zero for
    static and sleeping bodies; work = integration_work(n); prof as in `forces`."""
    rotating = model_torque or has_user_torque or spins(omega)
    state = (pos, quat, vel, omega)
    body = (inv_mass, inertia, inv_inertia, data[ISO])
    loads = (user_force, user_force_offset, user_torque, has_user_force, has_user_torque)
    if code == EXPLICIT_EULER or code == SEMI_IMPLICIT_EULER:
        _euler(code == SEMI_IMPLICIT_EULER, h, data, state, body, loads, rotating, work, prof)
    elif code == VELOCITY_VERLET:
        _verlet(h, data, state, body, loads, rotating, work, prof)
    elif code == RK4:
        _rk4(h, data, state, body, loads, rotating, work, prof)
    else:
        raise ValueError("integrate_substep: unknown integrator code")
