"""Off-centre collisions turn the bodies (COURSE.md 5, impulse with rotation).

j = −(1 + C_R) (v̄_A − v̄_B)·n / (1/m_A + 1/m_B + [(I_A⁻¹(r_A×n))×r_A + (I_B⁻¹(r_B×n))×r_B]·n),
m_A v_A+ = m_A v_A− + j n, ω_B+ = ω_B− − I_B⁻¹ (r_B × j n) — computed here by
hand from the course's formula and compared with the engine.
"""
import numpy as np
import pytest

from physics_core import load_scene

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")

# a frictionless pair, so the normal impulse is the whole story
NO_FRICTION = [{"a": "teflon", "b": "teflon", "static": 0.0, "kinetic": 0.0}]


def course_impulse(mA, IA, rA, mB, IB, rB, n, vA, vB, wA, wB, e):
    """The course's j for bodies with diagonal inertia IA, IB (world frame here)."""
    vbar = (vA + np.cross(wA, rA)) - (vB + np.cross(wB, rB))
    kA = np.cross(np.cross(rA, n) / IA, rA)
    kB = np.cross(np.cross(rB, n) / IB, rB)
    return -(1.0 + e) * (vbar @ n) / (1.0 / mA + 1.0 / mB + (kA + kB) @ n)


@pytest.mark.parametrize("offset", [0.0, 0.1, 0.2, -0.25])
def test_sphere_hitting_a_box_off_centre_spins_it_as_the_course_says(offset):
    e, mA, mB, r = 0.5, 1.0, 2.0, 0.1
    half = np.array([0.1, 0.3, 0.1])
    w = load_scene({"dt": 1.0 / 240.0, "friction": NO_FRICTION, "effects": {"contacts": {}},
                    "bodies": [
                        {"name": "ball", "shape": {"type": "sphere", "radius": r}, "mass": mA,
                         "material": "teflon", "restitution": e, "position": [-0.5, offset, 0.0],
                         "velocity": [2.0, 0.0, 0.0]},
                        {"name": "box", "shape": {"type": "box", "half_extents": half.tolist()},
                         "mass": mB, "material": "teflon", "restitution": e, "position": [0.0, 0.0, 0.0]}]})
    for _ in range(120):
        w.step()
        if len(w.contacts) and w.contacts.impulse.max() > 0:
            break
    n = np.array([1.0, 0.0, 0.0])                            # from ball (a) to box (b)
    rA, rB = -r * n, np.array([-half[0], offset, 0.0])
    IA = np.full(3, 0.4 * mA * r * r)
    IB = mB / 3.0 * np.array([half[1] ** 2 + half[2] ** 2, half[0] ** 2 + half[2] ** 2,
                              half[0] ** 2 + half[1] ** 2])
    z = np.zeros(3)
    j = course_impulse(mA, IA, rA, mB, IB, rB, n, np.array([2.0, 0, 0]), z, z, z, e)
    ball, box = w.body("ball"), w.body("box")
    np.testing.assert_allclose(ball.velocity, [2.0 + j / mA, 0, 0], atol=1e-12)
    np.testing.assert_allclose(box.velocity, -j * n / mB, atol=1e-12)
    np.testing.assert_allclose(box.angular_velocity, -np.cross(rB, j * n) / IB, atol=1e-12)
    np.testing.assert_allclose(ball.angular_velocity, 0.0, atol=1e-12)
    assert w.contacts.impulse.sum() == pytest.approx(-j, rel=1e-12)
    # momentum and angular momentum about any point are kept
    np.testing.assert_allclose(w.momentum(), [2.0 * mA, 0, 0], atol=1e-12)


def test_off_centre_hit_keeps_angular_momentum():
    w = load_scene({"dt": 1.0 / 240.0, "friction": NO_FRICTION, "effects": {"contacts": {}},
                    "bodies": [
                        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
                         "material": "teflon", "restitution": 0.7, "position": [-0.5, 0.17, 0.05],
                         "velocity": [2.0, 0.0, 0.0]},
                        {"name": "box", "shape": {"type": "box", "half_extents": [0.1, 0.3, 0.2]},
                         "mass": 2.0, "material": "teflon", "restitution": 0.7}]})
    L0 = w.angular_momentum()
    w.step(60)
    assert np.linalg.norm(w.body("box").angular_velocity) > 1.0
    np.testing.assert_allclose(w.angular_momentum(), L0, atol=1e-12)
