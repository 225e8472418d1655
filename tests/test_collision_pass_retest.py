"""The collision pass tests again, after its first sweep, only the contacts a
bounce reached since their last test (collision_pass._unchanged): a
contact whose bodies kept their velocities would not bounce now either.
With `retest_all` it tests every contact every sweep; both must give the
same bounces, bit for bit: on random clusters of spheres and boxes thrown
at each other and at the floor, and on a row of touching balls struck from
its last ball, where the blow passes one pair a sweep against key order
and ends in the first ball (COURSE.md 5: equal masses, C_R = 1, exchange
velocities).
"""
import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from physics_core import load_scene
from physics_core.collision.collision_pass import PASS_COLS, collision_pass
from physics_core.collision.contact_data import (END_WEIGHT, RESTITUTION_ITERATIONS,
                                                 RESTITUTION_RAMP, RESTITUTION_THRESHOLD)
from physics_scenes import box, scene, sphere
from substep_rows import rows_before_pass

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")
DT = 1.0 / 240.0


def _scene(bodies, mu=(0.4, 0.3)):
    return scene(*bodies, dt=DT, gravity=[0.0, 0.0, 0.0], effects={"contacts": {"sleep": False}},
                 friction=[{"a": "default", "b": "default", "static": mu[0], "kinetic": mu[1]}])


def _pass(w, rows, vel, omega, retest_all):
    """The pass on copies: (bounces, its outputs as bytes, the velocities)."""
    fp, ip = w.contact_system.fp, w.contact_system.ip
    R, I, M, MI = rows
    R, v, o = R.copy(), vel.copy(), omega.copy()
    k = len(R)
    target, tau, J = np.empty(k), np.empty(k), np.empty((k, 3))
    count = collision_pass(R, I, v, o, vel.copy(), omega.copy(), fp[RESTITUTION_THRESHOLD],
                           fp[RESTITUTION_RAMP], DT, fp[END_WEIGHT],
                           ip[RESTITUTION_ITERATIONS], target, tau, J,
                           np.full((k, PASS_COLS), 1e300), np.empty(len(vel) + 1, np.int64),
                           (M, MI), retest_all)
    return count, b"".join(x.tobytes() for x in (v, o, target, tau, J, R)), v


def _cluster(rng, n):
    """Spheres and boxes packed in a 0.5 m cube above a floor, each thrown at
    the cluster's centre, restitution 0.3 to 1."""
    bodies = [{"name": "floor", "shape": {"type": "plane"}, "static": True, "restitution": 0.8}]
    centre = np.array([0.0, 0.0, 0.3])
    for i in range(n):
        p = centre + rng.uniform(-0.25, 0.25, 3)
        p[2] = max(p[2], 0.09)
        v = (centre - p) * rng.uniform(5.0, 40.0) + rng.normal(0.0, 0.5, 3)
        make, size = ((sphere, float(rng.uniform(0.05, 0.1))) if rng.random() < 0.6
                      else (box, rng.uniform(0.04, 0.09, 3)))
        bodies.append(make(f"b{i}", size, float(rng.uniform(0.2, 5.0)), p,
                           restitution=float(rng.uniform(0.3, 1.0)), velocity=v.tolist(),
                           angular_velocity=rng.normal(0.0, 3.0, 3).tolist()))
    return bodies


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 30))
@example(seed=545, n=26)
def test_retesting_only_what_a_bounce_reached_gives_the_same_bounces(seed, n):
    """The pass's scratch table comes as a substep's scratch does, holding
    whatever was there (here 1e300 everywhere): a contact whose test time
    was read before any was written (the points of a manifold after the one
    that bounced, skipped in that sweep) was skipped in the next sweep too,
    and the pass bounced 42 times where testing every contact bounced 43
    (this example)."""
    rng = np.random.default_rng(seed)
    w = load_scene(_scene(_cluster(rng, n)))
    rows, vel, omega, _, _ = rows_before_pass(w, DT)
    skipped = _pass(w, rows, vel, omega, False)
    every = _pass(w, rows, vel, omega, True)
    assert skipped[0] == every[0]
    assert skipped[1] == every[1]


def test_a_row_struck_from_its_last_ball_passes_the_blow_to_the_first():
    """Five touching balls (m = 1 kg, C_R = 1, no friction), the last moving
    into the row at 3 m/s: the pass visits the pairs in key order, so each
    sweep bounces one pair further down the row, and the sweeps after the
    first skip every pair the blow has not reached. The first ball leaves
    at 3 m/s and the others stop (equal masses exchange velocities)."""
    r = 0.1
    balls = [sphere(f"b{i}", r, 1.0, (2.0 * r * i, 0.0, 1.0), restitution=1.0,
                    velocity=[-3.0 if i == 4 else 0.0, 0.0, 0.0]) for i in range(5)]
    w = load_scene(_scene(balls, mu=(0.0, 0.0)))
    rows, vel, omega, _, _ = rows_before_pass(w, DT)
    assert len(rows[0]) == 4
    skipped, every = (_pass(w, rows, vel, omega, flag) for flag in (False, True))
    assert skipped[0] == every[0] == 4               # one bounce a sweep, down the row
    assert skipped[1] == every[1]
    v = skipped[2]
    np.testing.assert_allclose(v[0], [-3.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(v[1:], 0.0, atol=1e-12)
