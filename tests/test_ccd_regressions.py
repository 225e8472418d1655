"""Time of impact never freezes a body (COURSE.md 5), regression tests.

The ccd stage used to count a rolling or spinning ball as fast (its surface
turns, though a sphere's shape does not move by turning) and, finding it
touching the floor at once, moved it back to its start pose every step: a
ball rolling at 6 m/s, or spinning at 200 rad/s in place, never moved again
while a held force kept raising its velocity. A rewound body also kept its
world-frame ω after being turned back, which changes the energy of an
asymmetric body.
"""

import numpy as np
import pytest

from physics_core import load_scene
from physics_scenes import box, scene, sphere

DT = 1.0 / 240.0
R = 0.1
GROUND = {"name": "ground", "shape": {"type": "plane"}, "static": True, "material": "steel"}


def floor_scene(*bodies, **contacts):
    return scene(GROUND, *bodies, dt=DT, gravity="earth",
                 effects={"contacts": dict(contacts)})


def test_ball_rolling_at_6_mps_is_not_frozen_by_ccd():
    """Rolling without slipping (v = ω r) on a flat floor: nothing slows it
    (no rolling resistance in the model), so after 1 s it is 6 m further."""
    ball = sphere(radius=R, position=(0, 0, R), velocity=[6.0, 0.0, 0.0],
                  angular_velocity=[0.0, 6.0 / R, 0.0], material="steel")
    world = load_scene(floor_scene(ball))
    world.step(240)
    b = world.body("ball")
    assert b.position[0] == pytest.approx(6.0, rel=1e-3)
    assert b.velocity[0] == pytest.approx(6.0, rel=1e-3)


def test_ball_spinning_at_200_rad_s_in_place_is_not_frozen_by_ccd():
    """A ball spinning about the vertical keeps its spin (no torsional
    friction) and can still be pushed: 1 N for 1 s on 1 kg moves it."""
    ball = sphere(radius=R, position=(0, 0, R), angular_velocity=[0.0, 0.0, 200.0],
                  material="steel")
    world = load_scene(floor_scene(ball))
    world.step(24)
    assert world.body("ball").angular_velocity[2] == pytest.approx(200.0, rel=1e-9)
    world.apply_force("ball", [0.0, 1.0, 0.0])
    world.step(240)
    assert world.body("ball").position[1] > 0.2


def test_held_force_moves_the_ball_instead_of_raising_a_frozen_velocity():
    """examples/push_and_follow.py --force -50 0 0: a 1 kg ball pushed by 50 N
    rolls away; its displacement and velocity agree (x = v t / 2, from rest)."""
    ball = sphere(radius=R, position=(0, 0, R), material="steel")
    world = load_scene(floor_scene(ball))
    world.step(10)
    world.apply_force("ball", [-50.0, 0.0, 0.0])
    x0 = world.body("ball").position[0]
    world.step(240)
    b = world.body("ball")
    travelled = b.position[0] - x0
    assert travelled < -5.0
    assert travelled == pytest.approx(0.5 * b.velocity[0] * 1.0, rel=0.02)


def test_box_spinning_on_the_floor_keeps_spinning_and_is_not_rewound():
    """A box spinning about z at 50 rad/s on the floor (fast by its turn):
    it touches the floor from the start, so ccd leaves it to the contacts."""
    crate = box("crate", half_extents=(0.1, 0.1, 0.1), position=(0, 0, 0.1),
                angular_velocity=[0.0, 0.0, 50.0], material="steel")
    world = load_scene(floor_scene(crate))
    q0 = world.body("crate").orientation
    world.step(12)
    assert not np.allclose(world.body("crate").orientation, q0)
    assert world.body("crate").angular_velocity[2] > 10.0


@pytest.mark.parametrize("seed", range(40))
def test_rewinding_a_fast_spinning_box_never_adds_energy(seed):
    """A box (50 m/s, 100 rad/s about a random axis) against a thin static
    wall, C_R = 0, no gravity: kinetic energy never rises above its start
    (the rewind keeps the body-frame angular velocity, hence ½ ω_b·I ω_b)."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    crate = box("crate", half_extents=(0.2, 0.1, 0.05), position=(-1.0, rng.uniform(-0.1, 0.1), 0.0),
                orientation=q.tolist(), velocity=[50.0, 0.0, 0.0],
                angular_velocity=(100.0 * axis).tolist(), restitution=0.0)
    wall = box("wall", half_extents=(0.005, 1.0, 1.0), position=(0.0, 0.0, 0.0), static=True)
    world = load_scene(scene(crate, wall, dt=DT, effects={"contacts": {"sleep": False}}))
    free = load_scene(scene(crate, dt=DT))
    e0 = world.kinetic_energy()
    highest, free_error = e0, 0.0
    for _ in range(60):
        world.step()
        free.step()
        highest = max(highest, world.kinetic_energy())
        free_error = max(free_error, abs(free.kinetic_energy() / e0 - 1.0))
    # the free-rotation splitting itself moves the energy of this tumbling box by
    # free_error (about 3e-5 at ω h = 0.42 rad); the contacts and rewinds add nothing
    assert highest <= e0 * (1.0 + 3.0 * free_error + 1e-12)
    assert world.body("crate").position[0] < 0.0      # never through the wall


@pytest.mark.parametrize("halvings", [1, 2, 4])
def test_ball_with_few_ccd_halvings_is_not_frozen_short_of_a_wall(halvings):
    """With 1–2 halvings the bisection used to leave a 50 m/s ball 2 cm short
    of a 4 cm wall, beyond the contact margin: no contact formed and the ball
    was moved back to the same pose every step, never bouncing. The
    bisection now goes on while the pose found is out of contact reach: the
    elastic ball bounces back at 50 m/s in the step it arrives."""
    wall = {"name": "wall", "shape": {"type": "box", "half_extents": [0.02, 1.0, 1.0]},
            "static": True, "material": "steel", "restitution": 1.0}
    ball = {"name": "ball", "shape": {"type": "sphere", "radius": 0.05}, "mass": 0.01,
            "material": "steel", "restitution": 1.0, "position": [-(0.07 + 0.33), 0.0, 0.0],
            "velocity": [50.0, 0.0, 0.0]}
    world = load_scene(scene(wall, ball, dt=1.0 / 60.0, gravity=[0, 0, 0],
                             effects={"contacts": {"ccd_iterations": halvings,
                                                   "ccd_tolerance": 1e-12, "sleep": False}}))
    world.step(2)
    b = world.body("ball")
    assert b.velocity[0] == pytest.approx(-50.0, rel=1e-9)
    assert b.position[0] < -0.07


@pytest.mark.parametrize("speed, gap", [(5.0, 0.0), (20.0, 0.0005), (100.0, 0.0)])
def test_a_ball_touching_a_thin_wall_is_stopped_at_the_ccd_depth_instead_of_crossing_it(speed, gap):
    """Regression (ccd let a touching pair go eight times deeper before a hit):
    a 5 mm ball touching a 1 cm static wall (a gap within the 1 mm contact
    margin) and driven into it at `speed` crosses the whole wall within one
    substep, and in between it is never deeper than r + the wall's half
    thickness, 10 mm. The ccd stage lets a touching pair go ccd_threshold ×
    the thinner body's smallest half size (0.5 × 5 mm = 2.5 mm) deeper than
    it started before it counts as crossing, and stops it there: the C_R = 0
    ball ends at rest that deep in, short of it by at most the bisection's
    bracket (ccd_tolerance of the step's travel, v h 1e-4)."""
    r = half = 0.005
    wall = {"name": "wall", "shape": {"type": "box", "half_extents": [half, 0.5, 0.5]},
            "static": True, "material": "steel"}
    ball = {"name": "ball", "shape": {"type": "sphere", "radius": r}, "mass": 0.01, "material": "steel",
            "restitution": 0.0, "position": [-(half + r + gap), 0.0, 0.0], "velocity": [speed, 0.0, 0.0]}
    world = load_scene(scene(wall, ball, dt=DT, gravity=[0, 0, 0], effects={"contacts": {"sleep": False}}))
    deepest = 0.0
    for _ in range(20):
        world.step()
        deepest = max(deepest, world.body("ball").position[0] + half + r)
    allowed = max(-gap, 0.0) + 0.5 * min(r, half)
    assert allowed - speed * DT * 1e-4 <= deepest <= allowed
    assert np.linalg.norm(world.body("ball").velocity) <= 1e-12
