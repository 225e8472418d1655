"""Static friction as the course states it, for a whole face (COURSE.md 2:
static friction holds while the tangential force ≤ μ_s F_N; past it the
body slides with μ_k F_N). Regression tests for the per-point friction of a
box's four corners, whose impulses pointed partly sideways and cancelled
in pairs: the box slid at 0.95 μ_s m g (1.4–7 m) and held only up to
0.91–0.94 μ_s. The manifold's friction is now one anchor at its centre."""
import math
import warnings

import numpy as np
import pytest

from physics_core import load_scene

DT = 1.0 / 240.0
G = 9.81


def box_on_floor(block="steel", gravity=(0.0, 0.0, -G)):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_scene({"dt": DT, "gravity": list(gravity),
                           "effects": {"contacts": {"sleep": False}},
                           "bodies": [{"name": "floor", "shape": {"type": "plane"}, "static": True,
                                       "material": "steel"},
                                      {"name": "box", "mass": 2.0, "material": block,
                                       "restitution": 0.0, "position": [0, 0, 0.1],
                                       "shape": {"type": "box", "half_extents": [0.2, 0.2, 0.1]}}]})


@pytest.mark.parametrize("at", [None, [0.0, 0.0, 0.0]])
def test_box_pushed_at_099_mu_s_m_g_holds(at):
    """Pushed through its centre or along its bottom face: no slide in 3 s."""
    w = box_on_floor()
    w.step(120)
    x0 = w.state.pos[1].copy()
    w.apply_force("box", [0.99 * 0.6 * 2.0 * G, 0, 0], point=at)
    w.step(720)
    assert np.abs(w.state.pos[1] - x0).max() < 1e-5


def test_box_pushed_at_101_mu_s_m_g_slides_at_mu_k_rate():
    """Past the static bound it breaks away and slides with μ_k: a = F/m − μ_k g."""
    w = box_on_floor()
    w.step(120)
    w.apply_force("box", [1.01 * 0.6 * 2.0 * G, 0, 0])
    w.step(240)
    v1 = w.state.vel[1, 0]
    w.step(240)
    a = (w.state.vel[1, 0] - v1) / 1.0
    assert v1 > 0.5
    assert a == pytest.approx(1.01 * 0.6 * G - 0.4 * G, rel=0.01)


@pytest.mark.parametrize("block, mu_s", [("steel", 0.6), ("aluminium", 0.61), ("copper", 0.53)])
def test_box_on_an_incline_1_degree_below_the_friction_angle_holds(block, mu_s):
    """Gravity tilted by θ = atan(μ_s) − 1° against the floor's normal is an
    incline of θ: the box stays put for 3 s."""
    theta = math.atan(mu_s) - math.radians(1.0)
    w = box_on_floor(block, gravity=(G * math.sin(theta), 0.0, -G * math.cos(theta)))
    w.step(60)
    x0 = w.state.pos[1].copy()
    w.step(720)
    assert np.abs(w.state.pos[1] - x0).max() < 1e-4


@pytest.mark.parametrize("spin", [10.0, -10.0])
def test_a_box_spinning_flat_on_the_floor_is_stopped_by_the_twist_friction(spin):
    """Regression (the manifold's twist friction dropped): a box spinning
    about the floor's normal has no slip at the anchor, so only the twist
    row stops it. Its four corners carry m g and slide at distance
    r̄ = √(a² + b²) from the centre, so the friction torque is μ_k m g r̄
    (COURSE.md 2) and, with I_z = m (a² + b²)/3, the spin falls at
    α = 3 μ_k g / √(a² + b²) (52.6 rad/s² here; measured to 1e-9 once the
    contact has settled, 1e-6 allowed) until it stops at t = |ω0|/α, within
    a step; then it stays stopped and the box never moves sideways."""
    a, b, c, mu_k = 0.2, 0.1, 0.05, 0.4        # steel on steel
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        w = load_scene({"dt": DT, "gravity": [0.0, 0.0, -G], "effects": {"contacts": {"sleep": False}},
                        "bodies": [{"name": "floor", "shape": {"type": "plane"}, "material": "steel"},
                                   {"name": "box", "mass": 1.0, "material": "steel", "restitution": 0.0,
                                    "position": [0, 0, c], "angular_velocity": [0, 0, spin],
                                    "shape": {"type": "box", "half_extents": [a, b, c]}}]})
    alpha = 3.0 * mu_k * G / math.hypot(a, b)
    spins, stopped = [], None
    for _ in range(120):
        w.step()
        spins.append(w.body("box").angular_velocity[2])
        if stopped is None and abs(spins[-1]) < 1e-12:
            stopped = w.time
    rates = -np.sign(spin) * np.diff(spins[12:36]) / DT
    np.testing.assert_allclose(rates, alpha, rtol=1e-6)
    assert stopped == pytest.approx(abs(spin) / alpha, abs=DT)
    assert np.abs(spins[-60:]).max() < 1e-12
    assert np.linalg.norm(w.body("box").velocity[:2]) < 1e-12
    assert np.linalg.norm(w.body("box").position[:2]) < 1e-9
