"""Restitution and momentum in collisions, against closed forms (COURSE.md 5, 6).

The course's impulse j = −(1 + C_R) v_rel·n / (1/m_A + 1/m_B + …) gives the
post-collision velocities in closed form; each test sets up one of the
course's cases and compares.
"""
import numpy as np
import pytest

from physics_core import load_scene

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")


def ball(name, x, v=0.0, mass=1.0, e=1.0, radius=0.1, z=0.0, material="glass"):
    return {"name": name, "shape": {"type": "sphere", "radius": radius}, "mass": mass,
            "material": material, "restitution": e, "position": [x, 0.0, z], "velocity": [v, 0.0, 0.0]}


def free_scene(*bodies, **contacts):
    """No gravity: only the collision changes the velocities."""
    return {"dt": 1.0 / 240.0, "effects": {"contacts": dict(contacts)}, "bodies": list(bodies)}


def head_on_closed_form(m1, v1, m2, v2, e):
    """1-D collision: momentum kept and (v2' − v1') = −e (v2 − v1)."""
    p = m1 * v1 + m2 * v2
    return (p + m2 * e * (v2 - v1)) / (m1 + m2), (p + m1 * e * (v1 - v2)) / (m1 + m2)


@pytest.mark.parametrize("e", [1.0, 0.5, 0.0])
def test_head_on_collision_gives_closed_form_velocities(e):
    m1, v1, m2, v2 = 1.0, 2.0, 3.0, -1.0
    w = load_scene(free_scene(ball("a", -0.5, v1, m1, e), ball("b", 0.5, v2, m2, e)))
    p0 = w.momentum()
    w.step(120)   # they meet after ~0.27 s
    want1, want2 = head_on_closed_form(m1, v1, m2, v2, e)
    va, vb = w.body("a").velocity, w.body("b").velocity
    assert va[0] == pytest.approx(want1, abs=1e-12)
    assert vb[0] == pytest.approx(want2, abs=1e-12)
    assert np.abs(va[1:]).max() == 0.0 and np.abs(vb[1:]).max() == 0.0
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-14)


def test_elastic_head_on_keeps_kinetic_energy():
    w = load_scene(free_scene(ball("a", -0.5, 2.0, 1.0, 1.0), ball("b", 0.5, -1.0, 3.0, 1.0)))
    k0 = w.kinetic_energy()
    w.step(120)
    assert w.kinetic_energy() == pytest.approx(k0, rel=1e-12)


def test_different_restitutions_keep_momentum_and_use_the_effective_mass_rule():
    """One impulse on both bodies (momentum kept); the pair's C_R is each body's C_R
    weighted by the share of the velocity change it takes (restitution.py)."""
    m1, m2, e1, e2 = 1.0, 4.0, 0.9, 0.3
    w = load_scene(free_scene(ball("a", -0.5, 2.0, m1, e1), ball("b", 0.5, 0.0, m2, e2)))
    p0 = w.momentum()
    w.step(120)
    e = (e1 / m1 + e2 / m2) / (1.0 / m1 + 1.0 / m2)
    want1, want2 = head_on_closed_form(m1, 2.0, m2, 0.0, e)
    assert w.body("a").velocity[0] == pytest.approx(want1, abs=1e-12)
    assert w.body("b").velocity[0] == pytest.approx(want2, abs=1e-12)
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-14)


@pytest.mark.parametrize("rule, pick", [("min", min), ("max", max), ("mean", lambda a, b: 0.5 * (a + b))])
def test_restitution_combine_rules(rule, pick):
    w = load_scene(free_scene(ball("a", -0.5, 2.0, 1.0, 0.9), ball("b", 0.5, 0.0, 4.0, 0.3),
                              restitution_combine=rule))
    w.step(120)
    want1, _ = head_on_closed_form(1.0, 2.0, 4.0, 0.0, pick(0.9, 0.3))
    assert w.body("a").velocity[0] == pytest.approx(want1, abs=1e-12)


def test_against_the_floor_only_the_moving_bodys_restitution_counts():
    """The floor is infinitely massive: its own C_R has no say (COURSE.md 5)."""
    def rebound(floor_e):
        w = load_scene({"dt": 1.0 / 240.0, "effects": {"contacts": {}}, "bodies": [
            {"name": "floor", "shape": {"type": "plane"}, "restitution": floor_e},
            {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
             "restitution": 0.6, "position": [0, 0, 0.3], "velocity": [0, 0, -3.0]}]})
        w.step(40)
        return w.body("ball").velocity[2]
    assert rebound(0.0) == pytest.approx(1.8, abs=1e-12)
    assert rebound(1.0) == pytest.approx(1.8, abs=1e-12)


def test_bounce_heights_fall_as_e_to_the_2n():
    """h_n = e^{2n} h_0: each bounce keeps e of the speed, e² of the height.
    The step is cut into 4 substeps; the bounce is placed at its time of
    impact inside the substep, which leaves an O(g h) error (< 1.5 %)."""
    e, h0, r = 0.8, 1.0, 0.1
    w = load_scene({"dt": 1.0 / 240.0, "substeps": 4, "gravity": [0, 0, -9.81],
                    "effects": {"contacts": {}}, "bodies": [
                        {"name": "floor", "shape": {"type": "plane"}, "material": "concrete"},
                        {"name": "ball", "shape": {"type": "sphere", "radius": r}, "mass": 1.0,
                         "material": "rubber", "restitution": e, "position": [0, 0, h0 + r]}]})
    z = []
    for _ in range(int(2.7 * 240)):
        w.step()
        z.append(w.body("ball").position[2] - r)
    z = np.array(z)
    apex = z[1:-1][(z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])][:3]
    want = h0 * e ** (2 * np.arange(1, 4))
    np.testing.assert_allclose(apex, want, rtol=0.015)


def test_slow_contact_does_not_bounce():
    """Below restitution_threshold the contact is resting (COURSE.md 5): C_R = 0."""
    w = load_scene({"dt": 1.0 / 240.0, "gravity": "earth",
                    "effects": {"contacts": {"restitution_threshold": 0.5, "sleep": False}}, "bodies": [
                        {"name": "floor", "shape": {"type": "plane"}},
                        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
                         "restitution": 1.0, "position": [0, 0, 0.1], "velocity": [0, 0, -0.3]}]})
    w.step(24)
    assert abs(w.body("ball").velocity[2]) < 1e-9
    assert w.body("ball").position[2] == pytest.approx(0.1, abs=1e-3)


def test_restitution_ramp_scales_the_bounce_linearly():
    def rebound(speed, ramp):
        w = load_scene(free_scene(
            {"name": "wall", "shape": {"type": "plane", "normal": [1, 0, 0]}, "static": True},
            ball("ball", 0.3, -speed, 1.0, 0.8), restitution_threshold=0.5, restitution_ramp=ramp))
        w.step(60)
        return w.body("ball").velocity[0]
    assert rebound(1.0, 1.0) == pytest.approx(0.8 * 0.5 * 1.0, abs=1e-12)   # halfway up the ramp
    assert rebound(2.0, 1.0) == pytest.approx(0.8 * 2.0, abs=1e-12)         # above it
    assert rebound(1.0, 0.0) == pytest.approx(0.8, abs=1e-12)


def test_newtons_cradle_passes_the_speed_down_the_row():
    """Equal elastic balls a hair apart (more than one step's travel, 4 mm): each hit
    swaps two velocities, so the last ball leaves with v and the rest stop."""
    n, r, gap, v = 5, 0.1, 0.01, 1.0
    balls = [ball(f"b{i}", i * (2 * r + gap), v if i == 0 else 0.0) for i in range(n)]
    balls[0]["position"][0] -= 0.02
    w = load_scene(free_scene(*balls))
    p0, k0 = w.momentum(), w.kinetic_energy()
    w.step(60)
    vx = np.array([w.body(f"b{i}").velocity[0] for i in range(n)])
    np.testing.assert_allclose(vx, [0, 0, 0, 0, v], atol=1e-12)
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-14)
    assert w.kinetic_energy() == pytest.approx(k0, rel=1e-12)


@pytest.mark.parametrize("drop", [0.0123, 0.1, 0.3, 0.5])
def test_speculative_contact_closes_its_gap_an_inelastic_ball_lands_on_the_floor(drop):
    """Regression (speculative contacts could not close their gap): a contact
    found within the margin at the end of a substep started it s0 apart, and
    the normal row lets the pair close those s0 in the substep (u_n ≥ −s0/h,
    COURSE.md 5); a row asking u_n ≥ 0 stops a falling ball s0 above the
    floor, more than the 1 mm margin, and it hovers there. A C_R = 0 ball
    dropped from `drop` touches the floor within one step of the fall time
    √(2 drop / g) and then rests on it: gap at most rounding (1e-12 m),
    overlap at most one step's gravity sag g h² (measured: exactly 0)."""
    g, h, r = 9.81, 1.0 / 240.0, 0.1
    w = load_scene({"dt": h, "gravity": [0, 0, -g], "effects": {"contacts": {"sleep": False}},
                    "bodies": [{"name": "floor", "shape": {"type": "plane"}, "material": "steel"},
                               {"name": "ball", "shape": {"type": "sphere", "radius": r}, "mass": 1.0,
                                "material": "steel", "restitution": 0.0, "position": [0, 0, r + drop]}]})
    fall = np.sqrt(2.0 * drop / g)
    landed = None
    for _ in range(int(fall / h) + 48):          # 0.2 s past the landing
        w.step()
        if landed is None and w.body("ball").position[2] - r <= 1e-12:
            landed = w.time
    assert landed == pytest.approx(fall, abs=h)
    overlap = r - w.body("ball").position[2]
    assert -1e-12 <= overlap <= g * h * h
    assert abs(w.body("ball").velocity[2]) <= 1e-12
