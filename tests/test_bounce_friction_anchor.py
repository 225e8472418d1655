"""Regression: a box landing across two boxes left its plane in the collision
pass (physics_core/collision/bounce_friction.py).

Three cubes in the x–z plane, the top one landing at 2.3 m/s across the
two below (the speed the top rows of a pyramid of 10,000 boxes land at):
the scene is its own mirror image in y, so no body may move along y or
turn about x or z. The pass applied each corner's friction on the bounce
point by point in key order, two corners of one side of the face first,
and left the bodies moving at up to 4.78 mm/s along y and turning at
0.138 rad/s about z after one substep (1.46 mm/s and 0.027 rad/s with the
corners taken diagonal first). At the manifold's anchor the friction acts
on the whole face at once: 1.4e-10 m/s and 1.9e-9 rad/s. Over the first
second the boxes stay within 0.051 mm of their plane: the solve's sweeps,
which take a face's corners in key order too, leave them creeping along y
at 0.3 µm/s. Checked on the pass itself (rows_before_solve:
the rows of the impact substep, the pass applied), and over a second of
the scene.
"""
import numpy as np
import pytest

from physics_core import load_scene
from physics_core.collision.contact_layout import DIR, direction_columns
from substep_rows import pass_applied, rows_before_solve

DT = 1 / 240
HALF = 0.1
SPEED = 2.3
FLOOR = {"name": "floor", "shape": {"type": "plane"}, "static": True}


def cube(name, x, z, vz=0.0):
    return {"name": name, "shape": {"type": "box", "half_extents": [HALF] * 3}, "mass": 1.0,
            "position": [x, 0.0, z], "velocity": [0.0, 0.0, vz]}


def three_boxes():
    with pytest.warns(UserWarning, match="fallback"):
        return load_scene({"dt": DT, "gravity": "earth",
                           "effects": {"contacts": {"sleep": False}},
                           "bodies": [FLOOR, cube("left", -1.01 * HALF, HALF),
                                      cube("right", 1.01 * HALF, HALF),
                                      cube("top", 0.0, 3 * HALF + 0.002, -SPEED)]})


def _out_of_plane(vel, omega):
    """The largest y velocity (m/s) and x, z turn (rad/s) of the boxes."""
    return float(np.abs(vel[1:, 1]).max()), float(np.abs(omega[1:, [0, 2]]).max())


def test_box_landing_across_two_boxes_left_its_plane_in_the_pass():
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(three_boxes(), DT)
    assert np.abs(omega[1:, 1]).max() > 1.0       # the blow turns them in the plane
    drift, turn = _out_of_plane(vel, omega)
    # what is left is the pass's normal impulses converged to 1e-9 of their sum
    assert drift <= 1e-8 and turn <= 1e-7


def test_box_landing_across_two_boxes_stays_in_its_plane():
    w = three_boxes()
    for _ in range(240):
        w.step()
        assert np.abs(w.state.pos[1:, 1]).max() <= 1e-4     # m, over the first second


def _landing_box(mu_s, mu_k, velocity, omega):
    """No gravity: a 20 cm cube of 1 kg landing flat on the floor, C_R = 0.5."""
    return load_scene({"dt": DT, "gravity": [0.0, 0.0, 0.0],
                       "effects": {"contacts": {"sleep": False}},
                       "friction": [{"a": "default", "b": "default", "static": mu_s,
                                     "kinetic": mu_k}],
                       "bodies": [dict(FLOOR, restitution=0.5),
                                  {"name": "box", "shape": {"type": "box",
                                                            "half_extents": [HALF] * 3},
                                   "mass": 1.0, "restitution": 0.5,
                                   "position": [0.0, 0.0, HALF + 0.002],
                                   "velocity": velocity, "angular_velocity": omega}]})


@pytest.mark.parametrize("mu, vx, spin", [(0.3, 0.6, 6.0), (0.2, 0.7, 4.5)])
def test_a_box_sliding_onto_the_floor_flat_takes_its_friction_at_the_anchor(mu, vx, spin):
    """No gravity: a 20 cm cube of 1 kg sliding at 1 m/s lands flat at 1 m/s,
    C_R = 0.5, so its face's bounce impulse is Σλ = 1.5 N·s. At the face's
    centre, 0.1 m below the box's, a tangential impulse F changes the
    slip by F W_tt, W_tt = 1/m + r²/I = 1 + 0.01 / (0.2² / 6) = 2.5: 0.4 N·s
    stops it. Within μ Σλ (μ = 0.3: 0.45) it holds: v_x = 1 − 0.4 = 0.6 m/s
    and ω_y = 0.4 · 0.1 / I = 6 rad/s, the face rolling on the floor. Past
    it (μ = 0.2: 0.3) it slides: v_x = 0.7 m/s, ω_y = 4.5 rad/s, still
    slipping forwards at 0.25 m/s. No sideways speed or other turn, and
    the box leaves at C_R × 1 m/s."""
    w = _landing_box(mu, mu, [1.0, 0.0, -1.0], [0.0, 0.0, 0.0])
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT, g=0.0)
    np.testing.assert_allclose(vel[1], [vx, 0.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(omega[1], [0.0, spin, 0.0], atol=1e-10)


@pytest.mark.parametrize("mu_s, mu_k, vx, spin", [(0.3, 0.2, 0.6, 6.0), (0.25, 0.2, 0.7, 4.5)])
def test_a_box_landing_flat_holds_by_static_friction_and_slides_by_kinetic(mu_s, mu_k, vx, spin):
    """The case above with μ_s ≠ μ_k: stopping the slip takes 0.4 N·s of
    Σλ = 1.5 N·s. μ_s = 0.3 allows 0.45: it holds (v_x = 0.6 m/s, ω_y = 6
    rad/s), though μ_k Σλ = 0.3 could not stop it. μ_s = 0.25 allows 0.375:
    it slides and takes μ_k Σλ = 0.3 N·s (v_x = 0.7 m/s, ω_y = 4.5 rad/s),
    not the 0.375 of μ_s."""
    w = _landing_box(mu_s, mu_k, [1.0, 0.0, -1.0], [0.0, 0.0, 0.0])
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT, g=0.0)
    np.testing.assert_allclose(vel[1], [vx, 0.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(omega[1], [0.0, spin, 0.0], atol=1e-10)


@pytest.mark.parametrize("mu, spin", [(0.3, 0.0), (0.1, 5.0 - 0.1 * 1.5 * HALF * np.sqrt(2) * 150)])
def test_a_box_landing_flat_while_spinning_takes_the_twist_at_its_anchor(mu, spin):
    """A cube landing flat at 1 m/s while spinning at 5 rad/s about the
    vertical: its four corners bounce alike, Σλ = 1.5 N·s, and at the
    face's centre the friction has no slip to stop, only the twist: the
    impulse I_z ω_z = (0.2² + 0.2²)/12 × 5 = 0.0333 N·m·s stops it, within
    μ Σλ r̄ (r̄ = 0.1 √2 m, the corners' distance from the centre): 0.0636
    with μ = 0.3, so the spin stops; 0.0212 with μ = 0.1, which takes
    0.0212 / I_z = 3.18 rad/s off it. No slip, no tilt."""
    w = _landing_box(mu, mu, [0.0, 0.0, -1.0], [0.0, 0.0, 5.0])
    R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT, g=0.0)
    np.testing.assert_allclose(vel[1], [0.0, 0.0, 0.5], atol=1e-12)
    np.testing.assert_allclose(omega[1], [0.0, 0.0, spin], atol=1e-10)


def test_bounce_friction_is_shared_by_the_points_in_proportion_to_their_impulses():
    """A cube landing flat while turning about y (ω_y = 2 rad/s: its +x corners
    approach at 1.2 m/s, its −x corners at 0.8) and sliding along x: the
    corners bounce with different λ. The events' friction per point (the
    pass's J, in each point's tangents) is the anchor's impulse shared in
    proportion to each point's λ, and the shares add up to the box's
    change of momentum along the floor."""
    w = _landing_box(0.3, 0.3, [1.0, 0.0, -1.0], [0.0, 2.0, 0.0])
    v_before = w.state.vel[1].copy()
    (R, I, M, MI), vel, omega, quat, store, (_, _, J) = pass_applied(w, DT, g=0.0)
    lam = J[:, 0]
    assert len(lam) == 4 and lam.min() > 0.0 and lam.max() > 1.2 * lam.min()
    # each point's tangential share as a world vector
    t = direction_columns(DIR)
    share = J[:, 1:2] * R[:, t[3:6]] + J[:, 2:3] * R[:, t[6:9]]
    per_lambda = share / lam[:, None]
    np.testing.assert_allclose(per_lambda, np.broadcast_to(per_lambda[0], (4, 3)), atol=1e-12)
    tangential = (vel[1] - v_before) * 1.0            # m = 1 kg, the floor static
    np.testing.assert_allclose(share.sum(axis=0)[:2], tangential[:2], atol=1e-12)
    assert abs(share.sum(axis=0)[2]) <= 1e-12
