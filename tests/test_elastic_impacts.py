"""Elastic impacts keep kinetic energy, and bounces keep C_R's definition with
every integrator (COURSE.md 5, coefficient of restitution; COURSE.md 4).

Regression tests named after the defects they guard: with C_R = 1 and no
friction, a symmetric three-ball hit lost 64–75 % of its energy and broke
its symmetry (one restitution sweep after an inelastic solve), a 16-ball
break lost 46 %, and an elastic ball bounced higher every time with
velocity Verlet, RK4 and explicit Euler (the bounce reversed a speed that
gravity gave after the impact, and the integrators' staggered velocities).
"""
import warnings

import numpy as np
import pytest

from physics_core import load_scene

DT = 1.0 / 240.0
ICE = [{"a": "ice", "b": "ice", "static": 0.0, "kinetic": 0.0}]


def world(bodies, gravity=(0.0, 0.0, 0.0), integrator="semi_implicit_euler"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_scene({"dt": DT, "gravity": list(gravity), "integrator": integrator,
                           "effects": {"contacts": {"sleep": False}}, "friction": ICE,
                           "bodies": bodies})


def ball(name, pos, vel=(0.0, 0.0, 0.0), r=0.1, e=1.0):
    return {"name": name, "shape": {"type": "sphere", "radius": r}, "mass": 1.0,
            "material": "ice", "restitution": e, "position": list(pos), "velocity": list(vel)}


@pytest.mark.parametrize("phase", [0.0, 0.25, 0.5, 0.75])
def test_three_equal_balls_symmetric_elastic_hit_keeps_energy_and_symmetry(phase):
    """Two balls at ±2 m/s hit a resting middle one at once: the closed form
    (simultaneous elastic impacts of equal masses) sends the outer ones back
    at ∓2 m/s and leaves the middle one at rest, wherever in the step the
    impact falls (`phase`, a fraction of a step's travel)."""
    gap = 0.3 + phase * 2.0 * DT
    w = world([ball("l", (-gap, 0, 0), (2, 0, 0)), ball("m", (0, 0, 0)),
               ball("r", (gap, 0, 0), (-2, 0, 0))])
    e0 = w.kinetic_energy()
    w.step(240)
    assert w.kinetic_energy() == pytest.approx(e0, rel=0.01)
    np.testing.assert_allclose(w.state.vel[:, 0], [-2.0, 0.0, 2.0], atol=0.02)


def test_sixteen_ball_billiards_break_keeps_energy_and_momentum():
    bodies = [ball("cue", (-1.0, 0, 0), (5, 0, 0))]
    for row in range(5):
        for j in range(row + 1):
            bodies.append(ball(f"b{len(bodies)}", (row * 0.2 * np.sqrt(3) / 2 + 1e-9,
                                                   (j - row / 2) * 0.2, 0)))
    w = world(bodies)
    e0, p0 = w.kinetic_energy(), w.momentum()
    w.step(480)
    assert w.kinetic_energy() == pytest.approx(e0, rel=0.01)
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-12)


def test_hundred_sphere_elastic_gas_in_a_static_box_keeps_energy_for_10_s():
    """Within 2 %: collisions slower than restitution_threshold (0.5 m/s) are
    resting contact (C_R = 0) by design and take a little."""
    rng = np.random.default_rng(1)
    bodies = []
    for ax in range(3):
        for k, sgn in enumerate((-1, 1)):
            n = [0.0, 0.0, 0.0]
            n[ax] = -sgn
            bodies.append({"name": f"wall{ax}{k}", "static": True, "material": "ice",
                           "restitution": 1.0,
                           "shape": {"type": "plane", "normal": n, "offset": -1.0}})
    pts = []
    while len(pts) < 100:
        p = rng.uniform(-0.85, 0.85, 3)
        if all(np.linalg.norm(p - q) > 0.25 for q in pts):
            pts.append(p)
    bodies += [ball(f"g{i}", p, rng.normal(0, 2, 3)) for i, p in enumerate(pts)]
    w = world(bodies)
    e0 = w.kinetic_energy()
    w.step(2400)
    assert w.kinetic_energy() == pytest.approx(e0, rel=0.02)


@pytest.mark.parametrize("integrator", ["explicit_euler", "semi_implicit_euler",
                                        "velocity_verlet", "rk4"])
def test_elastic_ball_peak_height_is_kept_for_20_s_with_every_integrator(integrator):
    """C_R = 1 off a floor: every peak within 1 % of the drop height."""
    h0, r = 1.0, 0.1
    w = world([{"name": "floor", "shape": {"type": "plane"}, "static": True, "material": "ice",
                "restitution": 1.0}, ball("ball", (0, 0, h0 + r))],
              gravity=(0, 0, -9.81), integrator=integrator)
    z = np.empty(20 * 240)
    for i in range(len(z)):
        w.step()
        z[i] = w.state.pos[1, 2] - r
    peaks = z[1:-1][(z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])]
    assert len(peaks) >= 20
    np.testing.assert_allclose(peaks, h0, rtol=0.01)
