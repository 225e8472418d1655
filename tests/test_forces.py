"""Force effects against closed-form answers (COURSE.md 2).

Each test states its tolerance and why. Where the integrator is exact for the
motion (constant acceleration with velocity Verlet or RK4), the tolerance is
round-off; elsewhere RK4 at the default step is used so that the remaining
error is far below the tolerance, which is still tight enough to catch a
wrong coefficient (a factor ½, π or ρ).
"""
import math

import numpy as np
import pytest

from physics_core import load_scene
from physics_scenes import (G_COURSE, INTEGRATORS, box, axis_angle, g_of, oscillator, rotation_matrix,
                            scene, sphere)

DT = 1.0 / 240.0


# ---- uniform gravity ------------------------------------------------------

@pytest.mark.parametrize("planet, course_value", [("earth", 9.81), ("moon", 1.62), ("mars", 3.69)])
def test_planet_gravity_is_G_m_over_r_squared(planet, course_value):
    """g = G m / r² from the course's masses and radii; the course rounds to 2 decimals
    (Mars computes to 3.699, so 0.01 is the rounding tolerance)."""
    world = load_scene(scene(sphere(), gravity=planet))
    g = -world.model.gravity[2]
    assert g == pytest.approx(g_of(planet), rel=1e-12)
    assert abs(g - course_value) < 0.01
    assert world.model.gravity[:2].tolist() == [0.0, 0.0]


def test_gravity_at_altitude_falls_off_as_inverse_square():
    h = 4.0e5   # m, roughly the ISS
    world = load_scene(scene(sphere(), gravity={"planet": "earth", "altitude": h}))
    assert -world.model.gravity[2] == pytest.approx(g_of("earth", h), rel=1e-12)
    assert -world.model.gravity[2] == pytest.approx(9.81 * (6.377e6 / (6.377e6 + h)) ** 2, rel=2e-3)


@pytest.mark.parametrize("planet", ["earth", "moon", "mars"])
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_free_fall_matches_half_g_t_squared(planet, integrator):
    """z = z0 − ½ g t², v = −g t.

    Verlet and RK4 are exact for constant acceleration (tolerance: round-off,
    1e-9 m over 2 s). The Euler pair carry a known first-order offset:
    semi-implicit z_n = z0 − ½ g t (t + dt), explicit z_n = z0 − ½ g t (t − dt);
    the test holds each to its own closed form, so a wrong g or a wrong order
    of updates fails."""
    g = g_of(planet)
    world = load_scene(scene(sphere(position=(0, 0, 100.0)), gravity=planet, integrator=integrator))
    n = 480
    world.step(n)
    t = n * DT
    assert world.time == pytest.approx(t, rel=1e-15)
    offset = {"semi_implicit_euler": -0.5 * g * t * DT, "explicit_euler": 0.5 * g * t * DT}
    expected_z = 100.0 - 0.5 * g * t * t + offset.get(integrator, 0.0)
    b = world.body("ball")
    assert b.position[2] == pytest.approx(expected_z, abs=1e-9)
    assert b.velocity[2] == pytest.approx(-g * t, abs=1e-10)
    assert b.position[:2].tolist() == [0.0, 0.0] and b.velocity[:2].tolist() == [0.0, 0.0]


def test_vector_gravity_points_where_the_scene_says():
    world = load_scene(scene(sphere(), gravity=[0.0, -3.0, 0.0], integrator="velocity_verlet"))
    world.step(240)
    assert world.body("ball").position == pytest.approx([0.0, -0.5 * 3.0 * 1.0, 0.0], abs=1e-12)


def test_projectile_follows_the_parabola():
    """x = v0 cos α t, z = v0 sin α t − ½ g t² on Mars; Verlet is exact here (1e-9 m)."""
    v0, alpha = 20.0, math.radians(40.0)
    vx, vz = v0 * math.cos(alpha), v0 * math.sin(alpha)
    world = load_scene(scene(sphere(velocity=[vx, 0.0, vz]), gravity="mars", integrator="velocity_verlet"))
    g = g_of("mars")
    flight = 2.0 * vz / g
    n = int(flight / DT)
    err = 0.0
    for i in range(1, n + 1):
        world.step()
        t = i * DT
        p = world.body("ball").position
        err = max(err, abs(p[0] - vx * t), abs(p[2] - (vz * t - 0.5 * g * t * t)))
    assert err < 1e-9
    # the range formula v0² sin 2α / g, at the last step before landing
    assert world.body("ball").position[0] == pytest.approx(
        v0 ** 2 * math.sin(2 * alpha) / g * (n * DT / flight), rel=1e-12)


# ---- springs and dampers --------------------------------------------------

def _upward_crossings(t, x):
    """Times x crosses 0 upward, linearly interpolated (exact to O(dt³) where x'' = 0)."""
    i = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    return t[i] - x[i] * (t[i + 1] - t[i]) / (x[i + 1] - x[i])


def _record_x(world, n):
    xs = np.empty(n + 1)
    xs[0] = world.body("bob").position[0]
    for i in range(n):
        world.step()
        xs[i + 1] = world.state.pos[0, 0]
    return np.arange(n + 1) * world.dt, xs


def test_undamped_spring_oscillates_with_period_2pi_sqrt_m_over_k():
    """T = 2π √(m/k), amplitude kept (RK4, ω dt = 0.037: period to 1e-5, amplitude to 1e-5)."""
    k, m = 40.0, 0.5
    world = load_scene(oscillator(k, m, x0=0.3))
    t, x = _record_x(world, 1200)
    period = np.diff(_upward_crossings(t, x)).mean()
    assert period == pytest.approx(2 * math.pi * math.sqrt(m / k), rel=1e-5)
    w = math.sqrt(k / m)
    b = world.body("bob")
    assert math.hypot(b.position[0], b.velocity[0] / w) == pytest.approx(0.3, rel=1e-5)
    assert world.body("bob").position[1:].tolist() == [0.0, 0.0]


def test_damper_gives_damped_period_and_exponential_envelope():
    """x = e^(−γt) (cos ω_d t + γ/ω_d sin ω_d t), γ = c/2m, ω_d = √(k/m − γ²).

    Checked three ways: the whole trajectory (1e-6 m), the period from zero
    crossings (1e-5) and the ratio of successive peaks e^(−γ T_d) (1e-4)."""
    k, m, c = 40.0, 0.5, 0.4
    gamma = c / (2 * m)
    wd = math.sqrt(k / m - gamma ** 2)
    world = load_scene(oscillator(k, m, x0=1.0, damping=c))
    t, x = _record_x(world, 1200)
    exact = np.exp(-gamma * t) * (np.cos(wd * t) + gamma / wd * np.sin(wd * t))
    assert np.abs(x - exact).max() < 1e-6
    assert np.diff(_upward_crossings(t, x)).mean() == pytest.approx(2 * math.pi / wd, rel=1e-5)
    peaks = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
    # parabolic refinement of each sampled maximum
    a, b, cc = x[peaks - 1], x[peaks], x[peaks + 1]
    top = b - 0.125 * (cc - a) ** 2 / (a - 2 * b + cc)
    ratios = top[1:] / top[:-1]
    assert ratios == pytest.approx(np.full(len(ratios), math.exp(-gamma * 2 * math.pi / wd)), rel=1e-4)


def test_damper_alone_removes_energy_monotonically():
    """The damper's power −C v² ≤ 0 (COURSE.md 2): energy never rises."""
    world = load_scene(oscillator(40.0, 0.5, x0=0.2, damping=2.0, integrator="velocity_verlet"))
    energies = [world.energy()]
    for _ in range(480):
        world.step()
        energies.append(world.energy())
    assert np.all(np.diff(energies) <= 1e-12)
    assert energies[-1] < 0.01 * energies[0]


def test_spring_between_two_bodies_uses_the_reduced_mass():
    """Two free masses on a spring oscillate at ω = √(k/μ), μ = m_a m_b / (m_a + m_b),
    and their centre of mass does not move (momentum conserved)."""
    k, ma, mb = 50.0, 1.0, 3.0
    mu = ma * mb / (ma + mb)
    world = load_scene(scene(
        sphere("a", mass=ma, position=(-0.6, 0, 0)), sphere("b", mass=mb, position=(0.6, 0, 0)),
        springs=[{"a": "a", "b": "b", "stiffness": k, "rest_length": 1.0}], integrator="rk4"))
    t = np.arange(961) * DT
    gap = [1.2]
    for _ in range(960):
        world.step()
        gap.append(world.state.pos[1, 0] - world.state.pos[0, 0])
    stretch = np.array(gap) - 1.0
    assert np.abs(stretch - 0.2 * np.cos(math.sqrt(k / mu) * t)).max() < 1e-6
    com = (ma * world.state.pos[0] + mb * world.state.pos[1]) / (ma + mb)
    assert np.abs(com - [0.3, 0.0, 0.0]).max() < 1e-12


# ---- drag ------------------------------------------------------------------

def test_linear_drag_fall_approaches_terminal_velocity_exponentially():
    """m v' = m g − b v: v = v_t (1 − e^(−t/τ)), τ = m/b, v_t = g τ; z from its integral.
    RK4 at dt = 1/240 over 6 s: 1e-9 relative."""
    m, b = 2.0, 0.8
    g = g_of("earth")
    world = load_scene(scene(sphere(mass=m), gravity="earth", integrator="rk4",
                             effects={"drag": {"model": "linear", "b": b}}))
    tau, vt = m / b, g * m / b
    for step in (240, 1440):
        world.step(step - world.step_index)
        t = world.time
        assert world.body("ball").velocity[2] == pytest.approx(-vt * (1 - math.exp(-t / tau)), rel=1e-9)
        assert world.body("ball").position[2] == pytest.approx(
            -vt * (t - tau * (1 - math.exp(-t / tau))), rel=1e-9)


def test_per_body_linear_coefficient_overrides_the_effect_default():
    world = load_scene(scene(sphere("slow", drag={"b": 2.0}), sphere("free", position=(1, 0, 0)),
                             gravity="earth", integrator="rk4",
                             effects={"drag": {"model": "linear", "b": 0.0}}))
    world.step(240)
    g, tau = g_of("earth"), 1.0 / 2.0
    assert world.body("slow").velocity[2] == pytest.approx(-g * tau * (1 - math.exp(-1.0 / tau)), rel=1e-9)
    assert world.body("free").velocity[2] == pytest.approx(-g * 1.0, rel=1e-12)


def test_quadratic_drag_fall_follows_tanh():
    """m v' = m g − ½ ρ C_d A v²: v = v_t tanh(g t / v_t), v_t = √(2 m g / (ρ C_d A)).
    The sphere's default C_d (0.47) and reference area π r² are used; RK4, 1e-8 relative."""
    m, r, rho = 1.0, 0.1, 1.204
    g = g_of("earth")
    world = load_scene(scene(sphere(mass=m, radius=r, position=(0, 0, 1000.0)), gravity="earth",
                             integrator="rk4", effects={"drag": {"model": "quadratic", "fluid_density": rho}}))
    vt = math.sqrt(2 * m * g / (rho * 0.47 * math.pi * r * r))
    for step in (240, 2400):
        world.step(step - world.step_index)
        t = world.time
        assert -world.body("ball").velocity[2] == pytest.approx(vt * math.tanh(g * t / vt), rel=1e-8)
        # z = −(v_t²/g) ln cosh(g t / v_t)
        assert 1000.0 - world.body("ball").position[2] == pytest.approx(
            vt * vt / g * math.log(math.cosh(g * t / vt)), rel=1e-8)


def test_quadratic_drag_on_a_box_uses_its_projected_area():
    """A box falling face-down meets A = 4 h_x h_y; tilted by θ about x it meets
    A = 4 h_x (h_y cos θ + h_z sin θ). Its terminal speed is √(2 m g / (ρ C_d A)); after
    30 s (≥ 10 time constants) it is reached to 1e-6. (dt = 1/60 s: the terminal
    speed is a fixed point of RK4, so the step does not bias it.)"""
    h = (0.3, 0.2, 0.1)
    theta = 0.5
    world = load_scene(scene(
        box("flat", half_extents=h, mass=1.0),
        box("tilted", half_extents=h, mass=1.0, position=(5, 0, 0), orientation=axis_angle([1, 0, 0], theta)),
        gravity="earth", integrator="rk4", dt=1.0 / 60.0, effects={"drag": {"model": "quadratic"}}))
    world.step(1800)
    g, rho, cd = g_of("earth"), 1.204, 1.05
    for name, area in (("flat", 4 * h[0] * h[1]),
                       ("tilted", 4 * h[0] * (h[1] * math.cos(theta) + h[2] * math.sin(theta)))):
        vt = math.sqrt(2 * g / (rho * cd * area))
        assert -world.body(name).velocity[2] == pytest.approx(vt, rel=1e-6)


def test_drag_opposes_velocity_in_any_direction():
    """F ∥ −v: a sphere thrown sideways in zero gravity slows without turning (1e-12 rad)."""
    v0 = np.array([3.0, -4.0, 12.0])
    world = load_scene(scene(sphere(velocity=v0.tolist()), effects={"drag": {"model": "quadratic"}}))
    world.step(240)
    v = world.body("ball").velocity
    assert np.linalg.norm(v) < np.linalg.norm(v0)
    assert np.linalg.norm(np.cross(v / np.linalg.norm(v), v0 / np.linalg.norm(v0))) < 1e-12
    assert np.dot(v, v0) > 0


@pytest.mark.parametrize("side, law", [(0.98, "linear"), (1.02, "quadratic")])
def test_reynolds_drag_switches_at_the_threshold(side, law):
    """Re = ρ |v| L / μ with L = 2r. Below the threshold: Stokes, F = 3π μ L v;
    above: F = ½ ρ C_d π r² v². One explicit-Euler step in zero gravity measures
    F = m Δv / dt exactly; 1e-9 relative."""
    rho, mu, r, m, thr = 1.204, 1.81e-5, 0.01, 0.05, 100.0
    L = 2 * r
    v = side * thr * mu / (rho * L)
    world = load_scene(scene(sphere(radius=r, mass=m, velocity=[v, 0.0, 0.0]), integrator="explicit_euler",
                             effects={"drag": {"model": "reynolds", "reynolds_threshold": thr}}))
    world.step()
    force = -m * (world.body("ball").velocity[0] - v) / DT
    expected = 3 * math.pi * mu * L * v if law == "linear" else 0.5 * rho * 0.47 * math.pi * r * r * v * v
    other = 0.5 * rho * 0.47 * math.pi * r * r * v * v if law == "linear" else 3 * math.pi * mu * L * v
    assert force == pytest.approx(expected, rel=1e-9)
    assert abs(force - other) > 0.01 * expected   # the two laws differ here, so the test can tell


# ---- buoyancy --------------------------------------------------------------

FLOAT_HALF = (0.5, 0.5, 0.1)   # a flat raft: metacentric height > 0, so it floats upright


def _raft_scene(density, surface_z=0.0, tilt=0.0, **body):
    return scene(box("raft", half_extents=FLOAT_HALF, density=density,
                     orientation=axis_angle([1, 0, 0], tilt), **body),
                 gravity="earth", effects={"buoyancy": {"fluid_density": 1000.0, "surface_z": surface_z,
                                                        "linear_damping": 3000.0, "angular_damping": 300.0}})


@pytest.mark.parametrize("density, surface_z", [(300.0, 0.0), (700.0, 1.5)])
def test_floating_box_settles_at_draft_rho_body_over_rho_fluid_times_height(density, surface_z):
    """Archimedes: draft = ρ_body/ρ_fluid × height. With damping the box settles;
    after 8 s its centre is at surface − draft + h_z to 1e-5 m and at rest."""
    height = 2 * FLOAT_HALF[2]
    draft = density / 1000.0 * height
    world = load_scene(_raft_scene(density, surface_z, position=[0.0, 0.0, surface_z + 0.3]))
    world.step(1920)
    b = world.body("raft")
    assert b.position[2] == pytest.approx(surface_z - draft + FLOAT_HALF[2], abs=1e-5)
    assert np.linalg.norm(b.velocity) < 1e-4


def test_floating_sphere_of_half_the_fluid_density_floats_half_submerged():
    """A sphere of ρ_f/2 displaces half its volume: its centre rests on the surface
    (exact cap volume π h² (3r − h)/3); 1e-5 m."""
    world = load_scene(scene(sphere("buoy", radius=0.2, mass=None, density=500.0, position=(0, 0, 0.5)),
                             gravity="earth",
                             effects={"buoyancy": {"fluid_density": 1000.0, "linear_damping": 300.0}}))
    world.step(1920)
    assert world.body("buoy").position[2] == pytest.approx(0.0, abs=1e-5)


def test_submerged_sphere_sinks_with_reduced_gravity():
    """Fully under water, net force (ρ_b − ρ_f) V g: a = g (1 − ρ_f/ρ_b); Verlet, exact to 1e-9."""
    world = load_scene(scene(sphere("stone", mass=None, density=2500.0, position=(0, 0, -5.0)),
                             gravity="moon", integrator="velocity_verlet",
                             effects={"buoyancy": {"fluid_density": 1000.0}}))
    world.step(240)
    a = g_of("moon") * (1 - 1000.0 / 2500.0)
    assert world.body("stone").position[2] == pytest.approx(-5.0 - 0.5 * a, abs=1e-9)


def test_tilted_box_under_water_feels_rho_g_V_and_no_torque():
    """Wholly submerged, a box's buoyancy is ρ_f g V at its centre whatever its
    orientation: a = g (1 − ρ_f/ρ_b) straight down and it does not start turning
    (Verlet, 1e-9 m; ω exactly 0). A box above the water feels nothing."""
    q = axis_angle([1.0, 1.0, 0.0], 0.6)
    world = load_scene(scene(box("sunk", density=3000.0, position=(0, 0, -3.0), orientation=q),
                             box("dry", density=3000.0, position=(5, 0, 10.0), orientation=q),
                             gravity="earth", integrator="velocity_verlet",
                             effects={"buoyancy": {"fluid_density": 1000.0}}))
    world.step(240)
    g = g_of("earth")
    assert world.body("sunk").position == pytest.approx([0.0, 0.0, -3.0 - 0.5 * g * (1 - 1 / 3.0)], abs=1e-9)
    assert np.abs(world.body("sunk").angular_velocity).max() < 1e-12
    assert world.body("dry").position[2] == pytest.approx(10.0 - 0.5 * g, abs=1e-9)


@pytest.mark.parametrize("cells, tolerance", [(4, 0.10), (16, 0.01)])
@pytest.mark.parametrize("tilt", [0.05, 0.1])
def test_floating_raft_righting_moment_follows_its_metacentric_height(tilt, cells, tolerance):
    """Wall-sided hull at heel θ: righting moment M = m g GZ with
    GZ = sin θ (GM + ½ BM tan² θ), GM = KB + BM − KG, KB = T/2, BM = B²/(12 T),
    KG = H/2 (T draft, B beam, H height); valid while neither the bottom edge
    emerges nor the deck edge dips (tan θ · B/2 < T, here θ < 0.119 rad). The box is
    split into cells³ parts, each filled linearly over its vertical extent, which
    is exact upright and approximate tilted: measured within 8 % at the default 4
    cells and 0.5 % at 16, so 10 % and 1 % are allowed. A centre of buoyancy left
    at the cell centres would be off by far more."""
    hx, hy, hz = FLOAT_HALF
    density = 300.0
    draft = density / 1000.0 * 2 * hz
    world = load_scene(scene(box("raft", half_extents=FLOAT_HALF, density=density,
                                 position=(0, 0, hz - draft), orientation=axis_angle([1, 0, 0], tilt)),
                             gravity="earth", effects={"buoyancy": {"fluid_density": 1000.0, "cells": cells}}))
    s = world.state
    _, torque = world.forces(s.pos, s.quat, s.vel, s.omega)
    m = world.body("raft").mass
    bm = (2 * hy) ** 2 / (12 * draft)
    gm = draft / 2 + bm - hz
    gz = math.sin(tilt) * (gm + 0.5 * bm * math.tan(tilt) ** 2)
    assert torque[0, 0] == pytest.approx(-m * g_of("earth") * gz, rel=tolerance)
    assert abs(torque[0, 1]) < 1e-9 and abs(torque[0, 2]) < 1e-9


def test_tilted_floating_box_rights_itself():
    """A raft wider than it is tall has its metacentre above its centre of mass
    (GM = KB + BM − KG = 0.03 + 1/(12·0.06) − 0.1 ≈ 1.3 m), so a tilt produces a
    restoring torque: released at 0.3 rad it first turns back, then settles upright
    (tilt < 1e-3 rad after 10 s)."""
    world = load_scene(_raft_scene(300.0, tilt=0.3, position=[0.0, 0.0, 0.04]))

    def tilt():
        up = rotation_matrix(world.body("raft").orientation)[:, 2]
        return math.acos(min(1.0, up[2]))

    world.step(12)
    assert tilt() < 0.3 - 1e-3
    assert world.body("raft").angular_velocity[0] < 0    # turning back towards upright
    world.step(2388)
    assert tilt() < 1e-3


# ---- Newtonian gravitation ---------------------------------------------------

def test_gravitation_force_is_G_m1_m2_over_r_squared():
    """One explicit-Euler step measures F = m Δv / dt on both bodies (1e-9 relative),
    attractive along the line between them."""
    m1, m2, r = 1.0e3, 2.5e3, 2.0
    world = load_scene(scene(sphere("a", mass=m1), sphere("b", mass=m2, position=(0, r, 0)),
                             integrator="explicit_euler", effects={"gravitation": {}}))
    world.step()
    f = G_COURSE * m1 * m2 / r ** 2
    assert m1 * world.body("a").velocity / DT == pytest.approx([0.0, f, 0.0], rel=1e-9, abs=1e-30)
    assert m2 * world.body("b").velocity / DT == pytest.approx([0.0, -f, 0.0], rel=1e-9, abs=1e-30)


def test_gravitation_conserves_total_momentum_to_round_off():
    """Newton 3: the pair forces are equal and opposite, so Σ m v stays at its
    initial value; over 2000 steps of a 6-body cluster the drift is below
    1e-13 of Σ |m v|."""
    rng = np.random.default_rng(7)
    bodies = [sphere(f"s{i}", mass=float(rng.uniform(0.5, 5.0)), position=rng.uniform(-1, 1, 3),
                     velocity=[float(x) for x in rng.uniform(-0.3, 0.3, 3)]) for i in range(6)]
    world = load_scene(scene(*bodies, effects={"gravitation": {"G": 0.05}}))
    p0 = world.momentum()
    scale = float(np.sum(world.model.mass[:, None] * np.abs(world.state.vel)))
    world.step(2000)
    scale = max(scale, float(np.sum(world.model.mass[:, None] * np.abs(world.state.vel))))
    assert np.abs(world.momentum() - p0).max() < 1e-13 * scale
    assert np.abs(world.momentum() - p0).max() < 1e-13 * max(1.0, scale)
