"""Position correction (COURSE.md 4, push-out by pseudo-velocities): overlap
beyond `slop` is removed at `correction_rate` per substep and the slop itself
is left alone, so a resting contact stays warm instead of chattering.

A sphere spawned 2 cm into the floor (no sleep, so nothing freezes it early):
each substep removes the fraction rate = 0.2 of the excess over the slop
(the push, 0.2 × 1.5 cm × 240/s = 0.72 m/s, is under max_correction_speed),
so after n substeps the depth is slop + 0.8ⁿ × 1.5 cm, and it ends at the
slop. Regression guard for the mutation "position correction pushes out the
slop too" (every resting contact pushed to zero depth), which no test caught.
"""
import warnings

import pytest

from physics_core import load_scene
from physics_scenes import scene, sphere

R, START_DEPTH, SLOP, RATE = 0.1, 0.02, 0.005, 0.2


def _sunk_sphere():
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the friction table's fallback
        return load_scene(scene(ground, sphere("ball", radius=R, position=(0, 0, R - START_DEPTH)),
                                gravity="earth",
                                effects={"contacts": {"sleep": False, "slop": SLOP, "correction_rate": RATE}}))


def test_overlap_beyond_the_slop_goes_at_the_correction_rate_and_the_slop_stays():
    world = _sunk_sphere()
    world.step(24)
    depth = R - world.body("ball").position[2]
    # closed form above; 1e-9 m is round-off on coordinates of ~0.1 m over 24 substeps
    assert depth == pytest.approx(SLOP + (1 - RATE) ** 24 * (START_DEPTH - SLOP), abs=1e-9)
    world.step(456)
    depth = R - world.body("ball").position[2]
    assert depth == pytest.approx(SLOP, abs=1e-12)  # 0.8⁴⁸⁰ of the excess is left: nothing but round-off
    assert list(world.body("ball").velocity) == [0.0, 0.0, 0.0]  # pushed by pseudo-velocities only
