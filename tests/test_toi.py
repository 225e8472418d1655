"""Time of impact (COURSE.md 5): bisection finds the first touching time, and
fast thin-wall crossings are caught even when neither end of the step overlaps."""
import math

import numpy as np
import pytest

from physics_core import quaternion as qt
from physics_core.collision.detection import signed_depths
from physics_core.collision.geometry import Geometry
from physics_core.collision.time_of_impact import (CCD_TOLERANCE, fast_body_mask,
                                                   interpolate_poses, swept_pairs, time_of_impact)
from physics_core.collision.time_of_impact import slerp_rows as slerp
from physics_core.scene_loader import build_model
from physics_scenes import box, sphere

DT = 1.0 / 240.0
G = 9.81


def model_of(*bodies):
    return build_model({"dt": DT, "bodies": list(bodies)})


def ground():
    return {"name": "ground", "shape": {"type": "plane"}}


def ball(name="ball", r=0.1, pos=(0, 0, 1)):
    return sphere(name, radius=r, position=pos)


def brick(name, half, pos=(0, 0, 0), static=False):
    """A box; a static one keeps the default mass, which only gravitation would read."""
    return box(name, half_extents=half, position=pos, **({"static": True} if static else {}))


def ends(model):
    pos = np.array(model.initial["pos"])
    quat = np.array(model.initial["quat"])
    return pos.copy(), quat.copy(), pos.copy(), quat.copy()


def depth_at(model, prev_pos, prev_quat, pos, quat, a, b, t):
    pa, qa = interpolate_poses(prev_pos[[a]], prev_quat[[a]], pos[[a]], quat[[a]], [t])
    pb, qb = interpolate_poses(prev_pos[[b]], prev_quat[[b]], pos[[b]], quat[[b]], [t])
    g = Geometry.from_model(model)
    return signed_depths(g.kind, g.dims, np.array([a]), np.array([b]), pa, qa, pb, qb)[0]


# ---- sphere falling onto a plane ----------------------------------------------

@pytest.mark.parametrize("h0,v0", [(0.5, 0.0), (0.2, -30.0), (0.15, -80.0), (1.0, -200.0)])
def test_falling_sphere_hits_plane_at_the_analytic_time(h0, v0):
    """Free fall over one step, z(τ) = z0 + v0 τ - g τ²/2 (COURSE.md 4), from
    height h0 above touching; poses between the step ends move linearly, so
    the sphere touches at t* = (z0 - r) / (z0 - z1) of the step."""
    r = 0.1
    step = 0.05
    model = model_of(ground(), ball(r=r, pos=(0, 0, r + h0)))
    prev_pos, prev_quat, pos, quat = ends(model)
    z0 = r + h0
    z1 = z0 + v0 * step - 0.5 * G * step ** 2
    if z1 > r:                       # make sure the step ends below touching
        step = (v0 + math.sqrt(v0 ** 2 + 2 * G * (z0 - r + 0.05))) / G
        z1 = z0 + v0 * step - 0.5 * G * step ** 2
    pos[1, 2] = z1
    fast = fast_body_mask(model, prev_pos, pos)
    assert fast[1]
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    assert list(zip(a, b)) == [(0, 1)]
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b)
    assert hit[0]
    t_star = (z0 - r) / (z0 - z1)
    assert t[0] <= t_star + 1e-12 and t_star - t[0] < CCD_TOLERANCE
    # in time: the ballistic touch, z(τ) = r, is within one step's curvature of it
    tau = (v0 + math.sqrt(v0 ** 2 + 2 * G * (z0 - r))) / G
    assert abs(t[0] * step - tau) <= 0.5 * G * step ** 2 / abs(z0 - z1) * step + CCD_TOLERANCE * step


def test_tolerance_and_iterations_set_the_bracket():
    model = model_of(ground(), ball(pos=(0, 0, 1.1)))
    prev_pos, prev_quat, pos, quat = ends(model)
    pos[1, 2] = -0.9                  # touches at t* = 1.0 / 2.0
    for tol in (1e-2, 1e-4, 1e-8):
        t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, [0], [1], iterations=60,
                                tolerance=tol)
        assert hit[0] and 0.0 <= 0.5 - t[0] < tol
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, [0], [1], iterations=3,
                            tolerance=1e-12)
    assert hit[0] and 0.0 <= 0.5 - t[0] <= 1.0 / 2 ** 3


def test_no_hit_when_apart_at_the_end_or_overlapping_at_the_start():
    model = model_of(ground(), ball("high", pos=(0, 0, 2.0)), ball("resting", pos=(3, 0, 0.09)))
    prev_pos, prev_quat, pos, quat = ends(model)
    pos[1, 2] = 0.5                   # still above the ground
    pos[2, 2] = -0.5                  # already touching at the start
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, [0, 0], [1, 2])
    assert not hit.any() and np.all(t == 1.0)


def test_head_on_fast_spheres():
    model = model_of(ball("left", r=0.05, pos=(-5, 0, 0)), ball("right", r=0.05, pos=(5, 0, 0)))
    prev_pos, prev_quat, pos, quat = ends(model)
    pos[0, 0], pos[1, 0] = 5.0, -5.0  # they pass through each other: apart at both ends
    fast = fast_body_mask(model, prev_pos, pos)
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    assert list(zip(a, b)) == [(0, 1)]
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b)
    assert hit[0]
    assert t[0] == pytest.approx((10 - 0.1) / 20, abs=CCD_TOLERANCE)


def test_spinning_bar_tip_reaches_the_floor():
    """A bar (half 1 × 0.05 × 0.05) turning 90° about y over the step: the
    lowest corner is at z_c - (sin φ + 0.05 cos φ) with φ = t π/2 (slerp)."""
    zc = 0.6
    model = model_of(ground(), brick("bar", (1.0, 0.05, 0.05), (0, 0, zc)))
    prev_pos, prev_quat, pos, quat = ends(model)
    quat[1] = [math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0]
    assert fast_body_mask(model, prev_pos, pos, prev_quat=prev_quat, quat=quat)[1]
    assert not fast_body_mask(model, prev_pos, pos)[1], "no travel: fast only by its turn"
    fast = fast_body_mask(model, prev_pos, pos, prev_quat=prev_quat, quat=quat)
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b, tolerance=1e-7, iterations=60)
    assert hit[0]
    # sin φ + 0.05 cos φ = zc  →  φ = asin(zc / √(1 + 0.05²)) - atan(0.05)
    phi = math.asin(zc / math.hypot(1.0, 0.05)) - math.atan2(0.05, 1.0)
    assert t[0] == pytest.approx(phi / (math.pi / 2), abs=1e-6)


def test_slerp_is_unit_and_hits_the_ends():
    rng = np.random.default_rng(0)
    q0 = qt.normalize(rng.normal(size=(50, 4)))
    q1 = qt.normalize(rng.normal(size=(50, 4)))
    q1[:5] = q0[:5]                   # identical orientations: no 0/0
    q1[5:10] = -q0[5:10]              # the same rotation, other sign
    for t in (0.0, 0.3, 1.0):
        q = slerp(q0, q1, np.full(50, t))
        assert np.all(np.isfinite(q))
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
    same = lambda p, q: np.minimum(np.abs(p - q).max(1), np.abs(p + q).max(1))
    assert same(slerp(q0, q1, np.zeros(50)), q0).max() < 1e-12
    assert same(slerp(q0, q1, np.ones(50)), q1).max() < 1e-12


def test_fast_body_threshold():
    model = model_of(ground(), ball("a", r=0.1, pos=(0, 0, 1)), ball("b", r=0.1, pos=(1, 0, 1)))
    prev_pos, _, pos, _ = ends(model)
    pos[1, 0] += 0.049                # below 0.5 × r
    pos[2, 0] += 0.051
    assert fast_body_mask(model, prev_pos, pos, 0.5).tolist() == [False, False, True]
    assert fast_body_mask(model, prev_pos, pos, 0.2).tolist() == [False, True, True]


# ---- 500 m/s bullets against a 1 cm wall ----------------------------------------

def _bullet_trial(rng, shape):
    """A bullet crossing a 1 cm static wall (turned by up to 20°) at 500 m/s in
    one 1/240 s step, apart from the wall at both ends of the step."""
    wall_q = qt.normalize(np.concatenate([[1.0], rng.uniform(-0.17, 0.17, 3)]))
    wall_c = rng.uniform(-1, 1, 3)
    normal = qt.rotate(wall_q[None], np.array([[1.0, 0, 0]]))[0]
    if shape == "sphere":
        bullet = ball("bullet", r=0.01)
        reach = 0.01
    else:
        bullet = brick("bullet", (0.02, 0.006, 0.006))
        reach = math.sqrt(0.02 ** 2 + 2 * 0.006 ** 2)
    # direction within 40° of the wall normal, aimed at a point of the wall face
    d = normal + 0.6 * rng.uniform(-1, 1, 3)
    d /= np.linalg.norm(d)
    travel = 500.0 * DT
    aim = wall_c + qt.rotate(wall_q[None], np.array([[0.0, *rng.uniform(-0.7, 0.7, 2)]]))[0]
    before = rng.uniform(reach + 0.02, travel - reach - 0.03)
    start = aim - d * before
    end = start + d * travel
    model = model_of(brick("wall", (0.005, 1.0, 1.0), wall_c, static=True), bullet)
    prev_pos, prev_quat, pos, quat = ends(model)
    prev_quat[0] = quat[0] = wall_q
    prev_pos[1], pos[1] = start, end
    bq0 = qt.normalize(rng.normal(size=4))
    prev_quat[1] = bq0
    quat[1] = qt.multiply(qt.from_rotation_vector(rng.uniform(-1, 1, 3) * 0.5), bq0)
    return model, prev_pos, prev_quat, pos, quat


@pytest.mark.parametrize("shape", ["sphere", "box"])
def test_500_mps_bullet_never_tunnels_through_1cm_wall(shape):
    rng = np.random.default_rng(2024 if shape == "sphere" else 42)
    for trial in range(100):
        model, prev_pos, prev_quat, pos, quat = _bullet_trial(rng, shape)
        # neither end of the step overlaps: a discrete test alone would miss it
        assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, 0.0) <= 0
        assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, 1.0) <= 0
        fast = fast_body_mask(model, prev_pos, pos, prev_quat=prev_quat, quat=quat)
        assert fast.tolist() == [False, True]
        a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
        assert list(zip(a, b)) == [(0, 1)], f"trial {trial}: swept test missed the wall"
        t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b)
        assert hit[0], f"trial {trial}: tunnelled"
        # t is the last instant apart, and the pair overlaps just after it
        assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, t[0]) <= 0
        assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, t[0] + 2 * CCD_TOLERANCE) > 0
        # and nothing touched earlier: a dense scan finds no earlier overlap
        scan = np.linspace(0.0, t[0], 400)
        for s in scan[::40]:
            assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, s) <= 0


def test_bullet_beside_the_wall_is_not_a_hit():
    model = model_of(brick("wall", (0.005, 1.0, 1.0), (0, 0, 0), static=True), ball("bullet", r=0.01))
    prev_pos, prev_quat, pos, quat = ends(model)
    prev_pos[1] = [-1.0, 1.05, 0.0]   # passes 4 cm beyond the wall's edge
    pos[1] = [1.0, 1.05, 0.0]
    fast = fast_body_mask(model, prev_pos, pos)
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b)
    assert not hit.any()


def test_many_pairs_bisect_together():
    """100 balls falling from different heights onto the ground in one call."""
    heights = np.linspace(0.2, 5.0, 100)
    model = model_of(ground(), *[ball(f"b{k}", r=0.1, pos=(k, 0, h)) for k, h in enumerate(heights)])
    prev_pos, prev_quat, pos, quat = ends(model)
    pos[1:, 2] = -1.0
    fast = fast_body_mask(model, prev_pos, pos)
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    assert len(a) == 100
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b)
    assert hit.all()
    expect = (heights[b - 1] - 0.1) / (heights[b - 1] + 1.0)
    assert np.all((expect - t >= 0) & (expect - t < CCD_TOLERANCE))


def test_corner_dipping_into_the_floor_and_out_again_is_caught():
    """A bar turning a half turn about y in one step, above the floor at both
    ends: its end sweeps down through the floor and back up mid-step."""
    zc = 0.6
    model = model_of(ground(), brick("bar", (1.0, 0.05, 0.05), (0, 0, zc)))
    prev_pos, prev_quat, pos, quat = ends(model)
    quat[1] = [math.cos(math.pi / 2 * 0.98), 0.0, math.sin(math.pi / 2 * 0.98), 0.0]   # 176.4°
    assert depth_at(model, prev_pos, prev_quat, pos, quat, 0, 1, 1.0) <= 0
    fast = fast_body_mask(model, prev_pos, pos, prev_quat=prev_quat, quat=quat)
    a, b = swept_pairs(model, prev_pos, prev_quat, pos, quat, fast)
    assert list(zip(a, b)) == [(0, 1)]
    t, hit = time_of_impact(model, prev_pos, prev_quat, pos, quat, a, b, tolerance=1e-7, iterations=60)
    assert hit[0]
    phi = math.asin(zc / math.hypot(1.0, 0.05)) - math.atan2(0.05, 1.0)
    assert t[0] == pytest.approx(phi / (math.pi * 0.98), abs=1e-6)
