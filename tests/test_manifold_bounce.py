"""The points of one manifold bounce together (collision_pass.py).

Bounced point by point, the first corner of a box landing flat took the
whole blow and the box left the floor turning: a 20 cm cube dropped flat
from 5 cm with C_R = 0.5 spun at 3.8 rad/s and slid at 0.3 m/s. A face
that meets a face squarely must rebound as a whole: every point leaves at
C_R × its approach speed (COURSE.md 5), so the body rises straight, with
no spin and no sideways speed, and two equal boxes meeting face on face
follow the 1-D closed form. And a collision never adds kinetic energy,
however the box lands.
"""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core import load_scene
from substep_rows import rows_before_pass, rows_before_solve

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")
HALF = 0.1


def box(name, pos, vel=(0.0, 0.0, 0.0), e=0.5, omega=(0.0, 0.0, 0.0), quat=None):
    spec = {"name": name, "shape": {"type": "box", "half_extents": [HALF, HALF, HALF]},
            "mass": 1.0, "restitution": e, "position": list(pos),
            "velocity": list(vel), "angular_velocity": list(omega)}
    if quat is not None:
        spec["orientation"] = list(quat)
    return spec


def floor(e=0.5):
    return {"name": "floor", "shape": {"type": "plane"}, "static": True, "restitution": e}


def scene(*bodies, gravity=(0.0, 0.0, 0.0), substeps=1, mu=0.5):
    """Every body of the default material, μ_s = μ_k = mu between them."""
    return {"dt": 1.0 / 240.0, "substeps": substeps, "gravity": list(gravity),
            "effects": {"contacts": {"sleep": False}}, "bodies": list(bodies),
            "friction": [{"a": "default", "b": "default", "static": mu, "kinetic": mu}]}


@pytest.mark.parametrize("e", [0.5, 0.8, 1.0])
@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.003, -0.002)])
def test_a_box_landing_flat_rises_straight_without_spin(e, offset):
    """No gravity: the box meets the floor face first at 1 m/s and must leave
    at e m/s straight up, turning at no rate (to the pass's convergence,
    1e-9 of the impulse)."""
    w = load_scene(scene(floor(e), box("b", (offset[0], offset[1], HALF + 0.01), (0, 0, -1.0), e)))
    w.step(12)
    b = w.body("b")
    assert b.velocity[2] == pytest.approx(e, abs=1e-7)
    np.testing.assert_allclose(b.velocity[:2], 0.0, atol=1e-7)
    np.testing.assert_allclose(b.angular_velocity, 0.0, atol=1e-6)


@pytest.mark.parametrize("e", [0.5, 1.0])
def test_a_box_landing_flat_while_turning_leaves_each_corner_at_its_own_goal(e):
    """No gravity, no friction: the box lands flat at 1 m/s while turning at
    2 rad/s about y, so its +x corners approach at 1.2 m/s and its −x corners
    at 0.8. Each must leave at C_R × its own approach, which fixes the
    rebound: v_z − 0.1 ω_y = 1.2 e and v_z + 0.1 ω_y = 0.8 e, so v_z = e and
    ω_y = −2 e rad/s. The corners' impulses differ (0.85 and 0.65 N·s a
    side for e = 0.5), so the even share the pass starts from is not the
    answer: its sweeps over the points must converge to it."""
    w = load_scene(scene(floor(e), box("b", (0.0, 0.0, HALF + 0.002), (0, 0, -1.0), e,
                                       omega=(0.0, 2.0, 0.0)), mu=0.0))
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, 1.0 / 240.0, g=0.0)
    np.testing.assert_allclose(vel[1], [0.0, 0.0, e], atol=1e-9)
    np.testing.assert_allclose(omega[1], [0.0, -2.0 * e, 0.0], atol=1e-8)


def _rebound_apex(body, radius, e, drop, steps=45):
    """Highest point of the first rebound of `body` dropped on the floor under
    gravity, 4 substeps a step; and the largest |ω| on the way."""
    w = load_scene(scene(floor(e), body, gravity=(0.0, 0.0, -9.81), substeps=4))
    z, spin = [], 0.0
    for _ in range(steps):
        w.step()
        z.append(w.body("b").position[2] - radius)
        spin = max(spin, np.max(np.abs(w.body("b").angular_velocity)))
    z = np.array(z)
    return z[np.argmin(z):].max(), spin


def test_a_box_dropped_flat_rebounds_as_high_as_a_ball_without_turning():
    """Under gravity, dropped 5 cm: the box's rebound apex is the ball's (the
    same impact timing, COURSE.md 5), e² of the drop within the O(g h)
    error of that timing, and it never turns on the way."""
    e, drop = 0.5, 0.05
    ball = {"name": "b", "shape": {"type": "sphere", "radius": HALF}, "mass": 1.0,
            "restitution": e, "position": [0.0, 0.0, HALF + drop]}
    box_apex, spin = _rebound_apex(box("b", (0.0, 0.0, HALF + drop), e=e), HALF, e, drop)
    ball_apex, _ = _rebound_apex(ball, HALF, e, drop)
    assert box_apex == pytest.approx(ball_apex, abs=1e-9)
    assert box_apex == pytest.approx(e * e * drop, rel=0.03)
    assert spin < 1e-6


@pytest.mark.parametrize("e", [0.5, 1.0])
def test_two_boxes_meeting_face_on_face_follow_the_head_on_closed_form(e):
    """Equal boxes, one at rest, one at 1 m/s, faces squarely met: v1' = (1 − e)/2,
    v2' = (1 + e)/2 (momentum kept, separation at e × approach), no spin."""
    w = load_scene(scene(box("a", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), e),
                         box("b", (2 * HALF + 0.01, 0.0, 0.0), e=e), mu=0.0))
    w.step(12)
    assert w.body("a").velocity[0] == pytest.approx((1 - e) / 2, abs=1e-7)
    assert w.body("b").velocity[0] == pytest.approx((1 + e) / 2, abs=1e-7)
    for name in "ab":
        np.testing.assert_allclose(w.body(name).angular_velocity, 0.0, atol=1e-6)


def test_off_centre_boxes_meeting_face_on_face_leave_together_turning_alike():
    """Centres 1 and 2 mm apart across the faces: the patch's points all
    separate at e × approach, so the faces leave without turning against
    each other (equal ω, the impulse through the centres' midpoint), and
    momentum and angular momentum are kept."""
    e = 0.5
    w = load_scene(scene(box("a", (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), e),
                         box("b", (2 * HALF + 0.01, 0.001, -0.002), e=e), mu=0.0))
    p0, l0 = w.momentum(), w.angular_momentum()
    w.step(12)
    a, b = w.body("a"), w.body("b")
    np.testing.assert_allclose(a.angular_velocity, b.angular_velocity, atol=1e-7)
    assert np.linalg.norm(a.angular_velocity) > 0.1          # the impulse is off both centres
    np.testing.assert_allclose(w.momentum(), p0, atol=1e-12)
    np.testing.assert_allclose(w.angular_momentum(), l0, atol=1e-12)
    # the faces' relative normal velocity, (v_b − v_a) + ω × (c_a − c_b) along x
    apart = b.velocity - a.velocity + np.cross(a.angular_velocity, a.position - b.position)
    assert apart[0] == pytest.approx(e, abs=1e-7)


def _kinetic(w):
    return w.kinetic_energy()


@settings(max_examples=40, deadline=None)
@given(tilt=st.floats(-0.3, 0.3), axis=st.floats(0.0, 2 * np.pi),
       spin=st.lists(st.floats(-8.0, 8.0), min_size=3, max_size=3),
       side=st.floats(-1.0, 1.0), e=st.floats(0.0, 1.0), mu=st.floats(0.0, 1.0))
def test_a_box_landing_any_way_never_gains_kinetic_energy(tilt, axis, spin, side, e, mu):
    """No gravity, any tilt, spin, sideways speed, C_R and friction: the kinetic
    energy after the impacts is at most what it was before (1e-9 for rounding)."""
    q = [np.cos(tilt / 2), np.sin(tilt / 2) * np.cos(axis), np.sin(tilt / 2) * np.sin(axis), 0.0]
    reach = HALF * (abs(np.cos(tilt)) + 2 * abs(np.sin(tilt)))
    w = load_scene(scene(floor(e), box("b", (0.0, 0.0, reach + 0.012), (side, 0.0, -1.5), e,
                                       spin, q), mu=mu))
    k0 = _kinetic(w)
    for _ in range(24):
        w.step()
        assert _kinetic(w) <= k0 * (1 + 1e-9)


def test_a_manifolds_rows_leave_their_tangent_block_to_the_bounce_that_needs_it():
    """A face's rows take their friction from the manifold's anchor, so the
    rows are built without the tangent block a single point's friction reads
    (NaN there: a reader would fail the step's finite check); their bounce
    takes its friction at the anchor too (bounce_friction.py), and a point
    that bounces alone (collision_pass._one_by_one) computes the block
    then. A cube landing flat while sliding (its points bounce with
    friction) must come out of the pass bit for bit as from rows built
    with the block."""
    from physics_core.collision import contact_stages as CS
    from physics_core.collision.contact_build import effective_masses
    from physics_core.collision.contact_layout import G_TN, MASS_N, W_TT
    from physics_core.collision.manifold_friction import COUNT, FIRST
    dt = 1.0 / 240.0
    w = load_scene(scene(floor(0.5), box("b", (0.0, 0.0, HALF + 0.002), (1.0, 0.3, -2.0)),
                         {"name": "ball", "shape": {"type": "sphere", "radius": 0.1},
                          "mass": 1.0, "restitution": 0.5, "position": [1.0, 0.0, 0.101],
                          "velocity": [0.5, 0.0, -2.0]}, mu=0.3))
    (R, I, M, MI), vel, omega, _, store = rows_before_pass(w, dt)
    block = slice(W_TT, G_TN + 2)
    counts = MI[:, COUNT]
    assert sorted(counts) == [1, 4]
    full = R.copy()
    for k in range(len(MI)):
        rows = range(MI[k, FIRST], MI[k, FIRST] + MI[k, COUNT])
        for c in rows:
            effective_masses(full, c)
            assert full[c, MASS_N] == R[c, MASS_N]
            if MI[k, COUNT] >= 2:
                assert np.isnan(R[c, block]).all()
            else:
                assert R[c, block].tobytes() == full[c, block].tobytes()
    outcomes, rising = [], []
    for rows in (R, full):
        v, o = vel.copy(), omega.copy()
        target, tau, J = CS.restitution_stage(w.contact_system.fp, w.contact_system.ip, rows, I,
                                              M.copy(), MI, v, o, vel.copy(), omega.copy(), dt,
                                              store)
        outcomes.append(b"".join(np.array(x).tobytes() for x in (v, o, target, tau, J)))
        assert (np.array(J)[:, 1:] != 0.0).any()      # friction on the bounce
        rising.append(v[1:, 2])
    assert outcomes[0] == outcomes[1]
    assert (rising[0] > 0.0).all()                     # both bodies bounced
