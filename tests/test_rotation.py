"""Rigid-body rotation (COURSE.md 3): torque, angular impulse, free rotation.

Angular momentum L = I_w ω with I_w = R diag(I) Rᵀ; a box with half extents
(a, b, c) has I = m/3 (b² + c², a² + c², a² + b²).
"""
import math

import numpy as np
import pytest

from physics_core import load_scene
from physics_scenes import INTEGRATORS, axis_angle, box, rotation_matrix, scene, sphere

DT = 1.0 / 240.0
HALF = (0.4, 0.25, 0.1)          # three distinct moments: x minor, y intermediate, z major


def box_inertia(m, half):
    a, b, c = half
    return m / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def world_inertia(q, moments):
    R = rotation_matrix(q)
    return R @ np.diag(moments) @ R.T


def body_frame(world, name, vec):
    return rotation_matrix(world.body(name).orientation).T @ vec


# ---- torque and angular impulse ---------------------------------------------

def test_constant_torque_spins_up_at_tau_over_I():
    """τ = I α about a principal axis: ω = τ t / I_z, no other component (1e-12)."""
    m, tau = 2.0, 0.3
    world = load_scene(scene(box(half_extents=HALF, mass=m)))
    world.apply_torque("box", [0.0, 0.0, tau])
    world.step(240)
    expected = tau * 1.0 / box_inertia(m, HALF)[2]
    assert world.body("box").angular_velocity == pytest.approx([0.0, 0.0, expected], abs=1e-12)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_torque_about_an_oblique_axis_changes_L_by_tau_t_in_every_component(integrator):
    """Regression (the torque kick of L had the wrong sign about x; every
    torque the tests applied lay along y or z): dL/dt = τ in the world frame
    (COURSE.md 3), so a held torque along an oblique axis, on an asymmetric
    box turned off its principal axes and starting at rest, gives L = τ t in
    each component, whatever the box's tumbling. Each integrator adds a
    constant τ to L exactly, so to round-off (1e-12 relative)."""
    q = axis_angle([1.0, -2.0, 0.5], 0.9)
    world = load_scene(scene(box(half_extents=HALF, mass=2.0, orientation=q), integrator=integrator))
    tau = np.array([0.3, -0.2, 0.5])
    world.apply_torque("box", tau)
    world.step(120)
    assert np.linalg.norm(world.body("box").angular_velocity) > 1.0     # it does turn
    assert world.angular_momentum() == pytest.approx(tau * world.time, rel=1e-12, abs=1e-12)


def test_off_centre_impulse_gives_omega_from_r_cross_J():
    """ω = I_w⁻¹ (r × J), v = J/m (COURSE.md 3, angular impulse), on a box turned
    away from its principal axes. With no torque afterwards L stays r × J exactly
    (1e-12), so it is checked after several steps too; ω right after the impulse
    is checked to first order in dt."""
    m = 3.0
    q = axis_angle([1.0, 2.0, -0.5], 0.7)
    centre = np.array([0.2, -0.1, 1.0])
    world = load_scene(scene(box(half_extents=HALF, mass=m, position=centre, orientation=q)))
    J = np.array([0.5, -1.0, 2.0])
    point = centre + np.array([0.3, 0.2, -0.05])
    world.apply_impulse("box", J, point=point)
    assert np.array_equal(world.body("box").velocity, np.zeros(3))    # applied at the next step
    world.step()
    b = world.body("box")
    I_w = world_inertia(b.orientation, box_inertia(m, HALF))
    L = np.cross(point - centre, J)
    assert b.velocity == pytest.approx(J / m, abs=1e-15)
    assert I_w @ b.angular_velocity == pytest.approx(L, abs=1e-12)
    omega0 = np.linalg.solve(world_inertia(q, box_inertia(m, HALF)), L)
    assert np.linalg.norm(b.angular_velocity - omega0) < 5 * DT * np.linalg.norm(omega0) ** 2
    world.step(100)
    assert world.angular_momentum() == pytest.approx(np.cross(point, J), abs=1e-12)


def test_impulse_through_the_centre_of_mass_does_not_turn_the_body():
    world = load_scene(scene(box(half_extents=HALF, mass=2.0, position=(1, 2, 3))))
    world.apply_impulse("box", [1.0, 2.0, 3.0], point=[1.0, 2.0, 3.0])
    world.step(10)
    assert np.array_equal(world.body("box").angular_velocity, np.zeros(3))
    assert world.body("box").velocity == pytest.approx([0.5, 1.0, 1.5], abs=1e-15)


def test_off_centre_force_produces_torque_r_cross_F():
    """A force held at a world point turns the body: after one explicit-Euler step
    from rest, v = F h / m and ω = I⁻¹ (r × F) h (1e-12 relative)."""
    m = 2.0
    world = load_scene(scene(box(half_extents=HALF, mass=m), integrator="explicit_euler"))
    F = np.array([0.0, 4.0, 0.0])
    r = np.array([0.4, 0.0, 0.0])
    world.apply_force("box", F, point=r)
    world.step()
    b = world.body("box")
    assert b.velocity == pytest.approx(F * DT / m, rel=1e-12)
    assert b.angular_velocity == pytest.approx(np.cross(r, F) * DT / box_inertia(m, HALF), rel=1e-12, abs=1e-18)


def test_off_centre_spring_attachment_produces_torque():
    """A stretched spring hooked at body offset r pulls with F = k (l − l₀) u there:
    after one explicit-Euler step from rest, ω = I⁻¹ (r × F) h. The same spring hooked
    at the centre leaves ω at exactly 0."""
    m, k = 2.0, 50.0
    anchor = np.array([0.0, 0.0, 1.0])
    r = np.array([0.3, 0.0, 0.1])

    def run(point):
        world = load_scene(scene(
            box(half_extents=HALF, mass=m), integrator="explicit_euler",
            springs=[{"a": "box", "b": "world", "stiffness": k, "rest_length": 0.2,
                      "point_a": [float(x) for x in point], "point_b": anchor.tolist()}]))
        world.step()
        return world.body("box").angular_velocity

    d = anchor - r
    F = k * (np.linalg.norm(d) - 0.2) * d / np.linalg.norm(d)
    assert run(r) == pytest.approx(np.cross(r, F) * DT / box_inertia(m, HALF), rel=1e-12, abs=1e-18)
    assert np.array_equal(run([0.0, 0.0, 0.0]), np.zeros(3))


@pytest.mark.parametrize("integrator, bound", [("semi_implicit_euler", 0.2), ("velocity_verlet", 0.03)])
def test_box_swinging_on_an_off_centre_spring_keeps_bounded_energy(integrator, bound):
    """A box hung by a corner from a stiff spring in gravity swings and tumbles
    (springs, gravity, torque and free rotation all at work). The symplectic pair
    show a bounded energy error (measured: 14 % and 1.6 % of E0, the sampled energy
    of a fast spring mode) that does not grow: the worst error in the last of 5
    seconds is within 5 % of the worst in the first."""
    world = load_scene(scene(
        box(half_extents=(0.1, 0.05, 0.05), mass=0.5, position=(0.3, 0.0, -0.4)),
        gravity="earth", integrator=integrator,
        springs=[{"a": "box", "b": "world", "stiffness": 2000.0, "rest_length": 0.3,
                  "point_a": [0.1, 0.0, 0.05], "point_b": [0.0, 0.0, 0.0]}]))
    E0 = world.energy()
    errors, turned = [], 0.0
    for _ in range(1200):
        world.step()
        errors.append(abs(world.energy() / E0 - 1.0))
        turned = max(turned, 2 * math.acos(min(1.0, abs(world.body("box").orientation[0]))))
    assert turned > 1.0
    assert max(errors) < bound
    assert max(errors[-240:]) < 1.05 * max(errors[:240])


# ---- free rotation -------------------------------------------------------------

# max |ΔE/E| over 10 s of a tumbling box at dt = 1/240 s. Measured: explicit Euler
# 4.5e-2 (drifts up), semi-implicit Euler and Verlet 1.5e-6 (bounded, second order),
# RK4 1.7e-10.
FREE_ENERGY_BOUND = {"explicit_euler": 0.1, "semi_implicit_euler": 5e-6, "velocity_verlet": 5e-6, "rk4": 1e-9}


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_torque_free_asymmetric_box_conserves_L_and_energy(integrator):
    """No torque: L (world) is conserved to round-off by every integrator (1e-11
    relative, they all carry L); the energy ½ ω·L within the bound above."""
    world = load_scene(scene(box(half_extents=HALF, mass=2.0, angular_velocity=[0.4, 3.0, 0.9]),
                             integrator=integrator))
    L0, E0 = world.angular_momentum(), world.energy()
    worst_L = worst_E = 0.0
    for _ in range(2400):
        world.step()
        worst_L = max(worst_L, np.linalg.norm(world.angular_momentum() - L0))
        worst_E = max(worst_E, abs(world.energy() / E0 - 1.0))
    assert worst_L < 1e-11 * np.linalg.norm(L0)
    assert worst_E < FREE_ENERGY_BOUND[integrator]
    if integrator == "explicit_euler":
        assert worst_E > 1e-3           # its orientation drift is real, and the symplectic fix matters


@pytest.mark.parametrize("integrator", ["semi_implicit_euler", "velocity_verlet"])
def test_free_rotation_energy_error_is_second_order(integrator):
    """Halving dt divides the symplectic pair's bounded energy error by ~4 (2 ± 0.3 in log2)."""
    errors = []
    for dt in (1 / 60, 1 / 120):
        world = load_scene(scene(box(half_extents=HALF, mass=2.0, angular_velocity=[0.4, 3.0, 0.9]),
                                 integrator=integrator, dt=dt))
        E0, worst = world.energy(), 0.0
        for _ in range(int(round(3.0 / dt))):
            world.step()
            worst = max(worst, abs(world.energy() / E0 - 1.0))
        errors.append(worst)
    assert math.log2(errors[0] / errors[1]) == pytest.approx(2.0, abs=0.3)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_spin_about_the_intermediate_axis_flips(integrator):
    """Tennis-racket theorem: spin about the intermediate axis (y) with a 1 % nudge
    grows away exponentially (rate ω √((I_y − I_x)(I_z − I_y)/(I_x I_z)) ≈ 2.4 /s at
    ω = 5 rad/s), so within 6 s the body-frame ω_y reverses (< −0.9 ω)."""
    world = load_scene(scene(box(half_extents=HALF, mass=1.0, angular_velocity=[0.05, 5.0, 0.05]),
                             integrator=integrator))
    lowest = 5.0
    for _ in range(1440):
        world.step()
        lowest = min(lowest, body_frame(world, "box", world.body("box").angular_velocity)[1])
    assert lowest < -0.9 * 5.0


@pytest.mark.parametrize("axis", [0, 2], ids=["minor_axis", "major_axis"])
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_spin_about_the_major_or_minor_axis_is_stable(integrator, axis):
    """Spin about the axis of least or greatest inertia, nudged by 1 %, stays about
    that axis: over 6 s the body-frame component stays above 0.97 ω."""
    omega = [0.05, 0.05, 0.05]
    omega[axis] = 5.0
    world = load_scene(scene(box(half_extents=HALF, mass=1.0, angular_velocity=omega), integrator=integrator))
    lowest = 5.0
    for _ in range(1440):
        world.step()
        lowest = min(lowest, body_frame(world, "box", world.body("box").angular_velocity)[axis])
    assert lowest > 0.97 * 5.0
