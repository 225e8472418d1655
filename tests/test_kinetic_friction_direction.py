"""Kinetic friction acts against the slip a contact is left with (COURSE.md 2
and 5), so the solver's friction update settles instead of flipping.

Bug guarded: a sliding contact's update took μ_k λ_n along the slip before
the update, which already carries the contact's old impulse. When the free
slip was between one and two times what μ_k λ_n can take off in a substep,
the direction flipped at every update: in a forming 1,000-sphere pile a
sphere's friction traded between two directions 100° apart and its spin
between −1.5 and 3.5 rad/s, sweep after sweep, so the result depended on
the parity of the sweep count and the shock-propagation sweep ran to its
pass cap on every layer.
"""
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from physics_core import load_scene
from physics_core.collision.kinetic_bound import kinetic_bound

G, R, MU_K, DT = 9.81, 0.1, 0.4, 1.0 / 240.0
W = 1.0 + R * R / (0.4 * R * R)       # a unit sphere's tangential 1/m_eff at its contact, 3.5 /kg
LIM = MU_K * G * DT                   # μ_k λ_n of one step, N·s


def ball(iterations):
    return load_scene({
        "dt": DT, "gravity": [0, 0, -G],
        "effects": {"contacts": {"sleep": False, "iterations": iterations, "velocity_tolerance": 0.0}},
        "friction": [{"a": "steel", "b": "steel", "static": 0.6, "kinetic": MU_K}],
        "bodies": [{"name": "floor", "shape": {"type": "plane"}, "material": "steel"},
                   {"name": "ball", "shape": {"type": "sphere", "radius": R}, "mass": 1.0,
                    "material": "steel", "restitution": 0.0, "position": [0, 0, R]}]})


def turned_slide(iterations):
    """A ball sliding along +y for a step (its warm friction points along −y
    and it still slips, 0.4 W μ_k g dt, so the next step is kinetic), then
    sent along +x at 1.4 times the slip one step of μ_k can take
    off, W μ_k m g dt: the case whose direction flipped. One more step."""
    w = ball(iterations)
    w.set_body_state("ball", velocity=[0.0, 1.4 * W * LIM, 0.0], angular_velocity=[0, 0, 0])
    w.step(1)
    w.set_body_state("ball", velocity=[1.4 * W * LIM, 0.0, 0.0], angular_velocity=[0, 0, 0])
    w.step(1)
    return w.body("ball").velocity.copy(), w.body("ball").angular_velocity.copy()


def test_sliding_friction_of_a_turned_slide_does_not_depend_on_the_sweep_count():
    """8, 9 and 10 sweeps end the step in the same state, to 1e-12 m/s (the
    bug: 8 and 9 differed by about W μ_k g dt = 0.057 m/s, the two sides of
    the flip)."""
    states = [turned_slide(n) for n in (8, 9, 10)]
    for v, w in states[1:]:
        assert np.allclose(v, states[0][0], rtol=0.0, atol=1e-12)
        assert np.allclose(w, states[0][1], rtol=0.0, atol=1e-12)


def test_the_slip_left_after_a_turned_slide_is_against_its_friction():
    """The ball's free slip was (1.4 W LIM, 0) and is left at
    (1.4 − 1) W LIM along +x, its friction μ_k m g dt along −x: the slip
    keeps its direction and shrinks by exactly W times the friction."""
    v, w = turned_slide(8)
    slip = v + np.cross(w, [0.0, 0.0, -R])             # contact-point velocity
    assert slip[0] == pytest.approx(0.4 * W * LIM, rel=1e-6)
    assert abs(slip[1]) < 1e-9 * W * LIM


@settings(max_examples=200, deadline=None)
@given(a11=st.floats(0.05, 20.0), a22=st.floats(0.05, 20.0), c=st.floats(-0.95, 0.95),
       angle=st.floats(0.0, 2 * math.pi), over=st.floats(1.0001, 50.0))
def test_kinetic_bound_leaves_a_slip_against_the_impulse_on_the_disk(a11, a22, c, angle, over):
    """For any symmetric positive A = W_tt⁻¹ and any λ* outside the disk
    |λ| ≤ lim: |λ| = lim to rounding, and the slip left, W (λ − λ*), is
    anti-parallel to λ (cosine −1 to 1e-9): the maximal-dissipation point."""
    A = np.array([[a11, c * math.sqrt(a11 * a22)], [c * math.sqrt(a11 * a22), a22]])
    lim = 1.0
    star = over * np.array([math.cos(angle), math.sin(angle)])
    lam = np.array(kinetic_bound(A[0, 0], A[0, 1], A[1, 1], star[0], star[1], lim))
    assert np.linalg.norm(lam) == pytest.approx(lim, rel=1e-12)
    left = np.linalg.solve(A, lam - star)
    cos = left @ lam / (np.linalg.norm(left) * np.linalg.norm(lam))
    assert cos == pytest.approx(-1.0, abs=1e-9)


@settings(max_examples=100, deadline=None)
@given(a11=st.floats(0.05, 20.0), a22=st.floats(0.05, 20.0), c=st.floats(-0.95, 0.95),
       angle=st.floats(0.0, 2 * math.pi), lim=st.sampled_from([1e-309, 1e-250, 1e-120, 1e-61]))
def test_a_tiny_friction_coefficient_does_not_make_the_solve_nan(a11, a22, c, angle, lim):
    """μ = 2.2e-309 between a box and the floor made the solve NaN: σ ~ |λ*|/lim
    overflowed (I + σA)'s determinant. Now λ is finite, on |λ| = lim, and
    the slip left is against it, as for any other lim."""
    A = np.array([[a11, c * math.sqrt(a11 * a22)], [c * math.sqrt(a11 * a22), a22]])
    star = 3.0 * np.array([math.cos(angle), math.sin(angle)])
    lam = np.array(kinetic_bound(A[0, 0], A[0, 1], A[1, 1], star[0], star[1], lim))
    assert np.all(np.isfinite(lam))
    unit = lam / lim                 # |λ| itself is below what a cosine can be taken of
    assert np.linalg.norm(unit) == pytest.approx(1.0, rel=1e-9)
    left = np.linalg.solve(A, lam - star)
    cos = left @ unit / (np.linalg.norm(left) * np.linalg.norm(unit))
    assert cos == pytest.approx(-1.0, abs=1e-9)


def test_a_box_sliding_on_a_floor_of_friction_1e_309_stays_finite():
    """The scene-level case of the one above: the box slides on, its speed kept
    (μ m g ~ 1e-308 N takes nothing off it)."""
    w = load_scene({"dt": 1 / 240, "gravity": "earth", "effects": {"contacts": {}},
                    "friction": [{"a": "default", "b": "default", "static": 2.2e-309,
                                  "kinetic": 2.2e-309}],
                    "bodies": [{"name": "floor", "shape": {"type": "plane"}, "static": True},
                               {"name": "b", "shape": {"type": "box", "half_extents": [0.1] * 3},
                                "mass": 1.0, "position": [0, 0, 0.1], "velocity": [1.0, 0, 0]}]})
    w.step(60)
    assert w.body("b").velocity[0] == pytest.approx(1.0, abs=1e-9)
