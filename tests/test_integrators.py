"""The four integrators (COURSE.md 4): order, invariants, and their cost in accuracy.

Measured on problems with closed-form answers: the harmonic oscillator
(convergence order), Kepler orbits (energy and angular-momentum drift),
uniform motion (Newton 1, bit for bit) and a stiff spring (automatic
sub-steps).
"""
import math

import numpy as np
import pytest

from physics_core import load_scene
from physics_core.effects.springs import MAX_OMEGA_H
from physics_scenes import INTEGRATORS, oscillator, scene, slope, sphere

# ---- convergence order ------------------------------------------------------

ORDER = {"explicit_euler": 1.0, "semi_implicit_euler": 1.0, "velocity_verlet": 2.0, "rk4": 4.0}


def oscillator_error(integrator, dt, duration=1.3):
    """Max over the run of the state error |x − cos ωt| + |v/ω + sin ωt|, ω = 2π rad/s."""
    w0 = 2.0 * math.pi
    world = load_scene(oscillator(w0 * w0, 1.0, x0=1.0, integrator=integrator, dt=dt))
    assert world.substeps == 1          # the step under test is the one we asked for
    err = 0.0
    for i in range(1, int(round(duration / dt)) + 1):
        world.step()
        t = i * dt
        err = max(err, abs(world.state.pos[0, 0] - math.cos(w0 * t))
                  + abs(world.state.vel[0, 0] / w0 + math.sin(w0 * t)))
    return err


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_integrator_converges_at_its_order_on_the_harmonic_oscillator(integrator):
    """Global error ∝ dt^p: the slope of log error against log dt over dt = 1/100,
    1/200, 1/400 s (ω dt ≤ 0.063) is p within ±0.15 (explicit Euler ~1, semi-implicit
    Euler ~1, velocity Verlet ~2, RK4 ~4)."""
    dts = [1 / 100, 1 / 200, 1 / 400]
    errors = [oscillator_error(integrator, dt) for dt in dts]
    assert slope(dts, errors) == pytest.approx(ORDER[integrator], abs=0.15)


def test_higher_order_integrators_are_more_accurate_at_the_same_step():
    errors = [oscillator_error(i, 1 / 100) for i in INTEGRATORS]
    assert errors[0] > errors[1] > errors[2] > errors[3]
    assert errors[3] < 1e-4 * errors[0]


# ---- Kepler orbits ------------------------------------------------------------

def kepler_run(integrator, eccentricity, orbits, steps_per_orbit=400):
    """A light planet (m = 1e-3) around a sun (M = 1) with G = 1, semi-major axis 1,
    started at periapsis with the vis-viva speed √(μ (1 + e) / r_p), from the
    centre of mass so the pair does not drift. Returns the relative energy and
    angular-momentum errors after every step, and the world."""
    M, m, e = 1.0, 1e-3, eccentricity
    mu = M + m
    rp = 1.0 - e
    vp = math.sqrt(mu * (1 + e) / rp)
    period = 2 * math.pi / math.sqrt(mu)
    dt = period / steps_per_orbit
    world = load_scene(scene(
        sphere("sun", mass=M, radius=0.01, position=(-m / mu * rp, 0, 0), velocity=[0.0, -m / mu * vp, 0.0]),
        sphere("planet", mass=m, radius=0.01, position=(M / mu * rp, 0, 0), velocity=[0.0, M / mu * vp, 0.0]),
        integrator=integrator, dt=dt, effects={"gravitation": {"G": 1.0}}))
    E0, L0 = world.energy(), world.angular_momentum()[2]
    dE, dL = [], []
    for _ in range(orbits * steps_per_orbit):
        world.step()
        dE.append(abs(world.energy() / E0 - 1.0))
        dL.append(abs(world.angular_momentum()[2] / L0 - 1.0))
    return np.array(dE), np.array(dL), world


# Circular orbit, 400 steps per orbit, 3 orbits: bound on max |ΔE/E| and |ΔL/L|.
# Measured: explicit Euler 0.26 / 0.19, semi-implicit 2.5e-4 / 1e-15,
# Verlet 1.5e-8 / 3e-15, RK4 5e-10 / 2.5e-10. The bounds sit ~4x above those.
CIRCULAR_BOUNDS = {
    "semi_implicit_euler": (1e-3, 1e-13),
    "velocity_verlet": (1e-7, 1e-13),
    "rk4": (2e-9, 1e-9),
}


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_circular_orbit_energy_and_angular_momentum_drift(integrator):
    """Energy E = ½ m v² − G M m / r and L = Σ r × m v are conserved by the physics.
    Symplectic Euler and Verlet keep L to round-off (a central force has no
    torque and their position update is along the new velocity); RK4 drifts a
    little; explicit Euler spirals out (energy rises by > 10 % in 3 orbits)."""
    dE, dL, world = kepler_run(integrator, 0.0, 3)
    if integrator == "explicit_euler":
        assert dE[-1] > 0.1 and dL[-1] > 0.05
        return
    e_bound, l_bound = CIRCULAR_BOUNDS[integrator]
    assert dE.max() < e_bound
    assert dL.max() < l_bound


def test_circular_orbit_closes_after_one_period_with_rk4():
    """After one period T = 2π √(a³/μ) the planet is back at its start (1e-6 of the radius)."""
    _, _, world = kepler_run("rk4", 0.0, 1)
    start = np.array([1.0 / 1.001, 0.0, 0.0])
    assert np.linalg.norm(world.body("planet").position - start) < 1e-6


def test_eccentric_orbit_rk4_drifts_far_less_than_explicit_euler():
    """e = 0.6, 400 steps per orbit, 4 orbits: RK4's energy error (measured 1.3e-6)
    is more than 1e4 times smaller than explicit Euler's (0.7)."""
    dE_euler, _, _ = kepler_run("explicit_euler", 0.6, 4)
    dE_rk4, dL_rk4, _ = kepler_run("rk4", 0.6, 4)
    assert dE_rk4.max() < 5e-6 and dL_rk4.max() < 5e-7
    assert dE_rk4.max() * 1e4 < dE_euler.max()


@pytest.mark.parametrize("integrator", ["semi_implicit_euler", "velocity_verlet"])
def test_eccentric_orbit_energy_error_stays_bounded_with_symplectic_integrators(integrator):
    """The symplectic pair conserve a nearby energy: the error oscillates within
    each orbit (largest at periapsis) but does not grow. Over 4 orbits of e = 0.6 the
    worst error in the last orbit is within 10 % of the worst in the first, while
    explicit Euler's grows by more than 50 %. L is kept to round-off (1e-13)."""
    dE, dL, _ = kepler_run(integrator, 0.6, 4)
    first, last = dE[:400].max(), dE[-400:].max()
    assert last < 1.1 * first
    assert dL.max() < 1e-13
    dE_euler, _, _ = kepler_run("explicit_euler", 0.6, 4)
    assert dE_euler[-400:].max() > 1.5 * dE_euler[:400].max()


# ---- Newton's first law ----------------------------------------------------------

@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_body_without_forces_keeps_its_velocity_bit_for_bit(integrator):
    """Newton 1 with no effects declared: v never changes, not even by one bit, and
    x is x0 + v dt added n times in floating point (exactly that sequence of
    additions for the Euler pair and Verlet; RK4 forms v dt as (h/6)(6 v), so it is
    held to 4 ulp per step)."""
    x0 = np.array([1.0, -2.0, 3.0])
    v = np.array([0.1, -0.37, 2.9])
    dt = 1.0 / 240.0
    world = load_scene(scene(sphere(position=x0, velocity=v.tolist()), integrator=integrator))
    n = 1000
    world.step(n)
    b = world.body("ball")
    assert np.array_equal(b.velocity, v)
    x = x0.copy()
    for _ in range(n):
        x = x + v * dt
    if integrator == "rk4":
        assert np.abs(b.position - x).max() <= 4 * n * np.spacing(np.abs(x).max())
    else:
        assert np.array_equal(b.position, x)
    assert np.abs(b.position - (x0 + n * v * dt)).max() < n * 4 * np.spacing(10.0)
    assert np.array_equal(b.orientation, [1.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_free_spinning_sphere_keeps_its_angular_velocity(integrator):
    """A sphere's inertia is isotropic, so with no torque ω is constant (round-off,
    1e-12 rad/s over 1000 steps) and its orientation turns at exactly |ω|."""
    w = np.array([0.3, -1.2, 2.0])
    world = load_scene(scene(sphere(angular_velocity=w.tolist()), integrator=integrator))
    world.step(1000)
    assert np.abs(world.body("ball").angular_velocity - w).max() < 1e-12
    theta = np.linalg.norm(w) * world.time
    expected = np.concatenate([[math.cos(theta / 2)], w / np.linalg.norm(w) * math.sin(theta / 2)])
    q = world.body("ball").orientation
    assert min(np.abs(q - expected).max(), np.abs(q + expected).max()) < 1e-9


# ---- stiff springs: automatic sub-steps -------------------------------------------

def test_spring_substeps_keep_omega_h_below_half():
    """ω = √(k/m) = 1000 rad/s at dt = 1/240 s needs ⌈ω dt / 0.5⌉ = 9 sub-steps; a
    damper of rate C/m = 1e4 /s needs ⌈1e4 dt / 0.5⌉ = 84; a soft spring and a
    scene without springs need 1; the scene's own substeps count when larger."""
    dt = 1.0 / 240.0
    stiff = load_scene(oscillator(1e6, 1.0, dt=dt))
    assert stiff.spring_substeps == math.ceil(1000.0 * dt / MAX_OMEGA_H) == 9
    assert stiff.substeps == 9
    assert 1000.0 * dt / stiff.substeps <= MAX_OMEGA_H
    assert load_scene(oscillator(1.0, 1.0, damping=1e4, dt=dt)).spring_substeps == 84
    assert load_scene(oscillator(40.0, 0.5, dt=dt)).spring_substeps == 1
    assert load_scene(scene(sphere())).spring_substeps == 1
    many = oscillator(40.0, 0.5, dt=dt)
    many["substeps"] = 12
    assert load_scene(many).substeps == 12


def test_off_centre_attachment_counts_the_rotational_inertia():
    """At offset r the spring sees 1/m_eff ≤ 1/m + r²/I_min: a 0.1 m sphere (I = 0.004)
    hung 0.1 m off-centre on k = 1e5 has ω ≤ √(1e5 (1 + 2.5)) = 592 rad/s."""
    sc = oscillator(1e5, 1.0, dt=1.0 / 240.0)
    sc["bodies"][0]["shape"]["radius"] = 0.1
    sc["springs"][0]["point_a"] = [0.1, 0.0, 0.0]
    world = load_scene(sc)
    assert world.spring_substeps == math.ceil(math.sqrt(1e5 * 3.5) / 240.0 / MAX_OMEGA_H)


def _aliased_period(x, dt):
    """Period of a sampled sinusoid that is faster than the sampling's Nyquist limit.

    A sinusoid sampled every dt obeys x[n+1] + x[n-1] = 2 cos(ω dt) x[n]; the least-
    squares cos(ω dt) gives ω dt up to aliasing, and here π < ω dt < 2π."""
    c = np.sum(x[1:-1] * (x[2:] + x[:-2])) / (2.0 * np.sum(x[1:-1] ** 2))
    return 2 * math.pi * dt / (2 * math.pi - math.acos(c))


def _run_stiff(integrator, seconds):
    """x after every step and E/E0 = (½ m v² + ½ k x²) / E0 (the motion stays on x)."""
    world = load_scene(oscillator(1e6, 1.0, x0=0.01, integrator=integrator, dt=1.0 / 240.0))
    n = int(round(seconds * 240))
    xs, vs = np.empty(n + 1), np.empty(n + 1)
    xs[0], vs[0] = 0.01, 0.0
    for i in range(1, n + 1):
        world.step()
        xs[i], vs[i] = world.state.pos[0, 0], world.state.vel[0, 0]
    assert world.energy() == pytest.approx(0.5 * vs[-1] ** 2 + 0.5e6 * xs[-1] ** 2, rel=1e-9)
    return xs, (0.5 * vs ** 2 + 0.5e6 * xs ** 2) / (0.5e6 * 0.01 ** 2), world


@pytest.mark.parametrize("integrator, seconds", [("semi_implicit_euler", 10.0), ("velocity_verlet", 5.0),
                                                 ("rk4", 2.0)])
def test_stiff_spring_stays_bounded_and_oscillates_at_its_period(integrator, seconds):
    """k = 1e6 N/m, m = 1 kg, dt = 1/240 s (ω dt = 4.2, unstable without sub-steps).

    With 9 automatic sub-steps (ω h = 0.463):
    - semi-implicit Euler conserves H̃ = E − ½ h ω² m x v exactly, so E/E0 stays in
      [1/(1 + ω h/2), 1/(1 − ω h/2)] = [0.81, 1.30];
    - Verlet's sampled energy stays in [1 − (ω h/2)², 1] = [0.946, 1];
    - RK4 only loses energy ((ω h)⁶/72 per sub-step).
    The period is T = 2π √(m/k) = 6.283 ms within 1.5 % (theory for the symplectic
    pair: ω̃ h = 2 asin(ω h / 2), 0.9 % short); the 240 Hz samples alias it, so it is
    read from the samples' recurrence."""
    xs, energies, world = _run_stiff(integrator, seconds)
    assert np.all(np.isfinite(xs)) and world.time == pytest.approx(seconds)
    wh = 1000.0 / 240.0 / world.substeps
    if integrator == "semi_implicit_euler":
        lo, hi = 1 / (1 + wh / 2), 1 / (1 - wh / 2)
    elif integrator == "velocity_verlet":
        lo, hi = 1 - (wh / 2) ** 2, 1.0
    else:
        lo, hi = 0.0, 1.0
    assert lo - 1e-6 <= energies.min() and energies.max() <= hi + 1e-6
    assert np.abs(xs).max() < 0.01 * math.sqrt(hi) + 1e-9
    period = _aliased_period(xs[:480], world.dt)
    assert period == pytest.approx(2 * math.pi / 1000.0, rel=0.015)
    if integrator != "rk4":
        discrete = 2 * math.pi / (2 * math.asin(wh / 2) / (world.dt / world.substeps))
        assert period == pytest.approx(discrete, rel=1e-6)
