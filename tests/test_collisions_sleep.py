"""Sleeping: bodies at rest leave the solver and wake when touched or commanded."""
import numpy as np
import pytest

from physics_core import load_scene

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")


def scene(**contacts):
    return {"dt": 1.0 / 240.0, "gravity": "earth",
            "effects": {"contacts": dict(sleep=True, sleep_time=0.5, **contacts)},
            "bodies": [{"name": "floor", "shape": {"type": "plane"}, "material": "steel"},
                       {"name": "box", "shape": {"type": "box", "half_extents": [0.2, 0.2, 0.1]},
                        "mass": 1.0, "material": "steel", "restitution": 0.0, "position": [0, 0, 0.1]},
                       {"name": "ball", "shape": {"type": "sphere", "radius": 0.05}, "mass": 0.2,
                        "material": "steel", "restitution": 0.0, "position": [3.0, 0, 1.0]}]}


def test_a_resting_box_falls_asleep_and_stays_put():
    w = load_scene(scene())
    w.step(60)
    assert w.state.awake[1]
    w.step(120)                                  # rested 0.5 s (and more)
    assert not w.state.awake[1]
    assert w.inv_mass[1, 0] == 0.0              # out of the solver
    p = w.body("box").position.copy()
    w.step(240)
    np.testing.assert_array_equal(w.body("box").position, p)


def test_a_falling_body_wakes_a_sleeping_one():
    w = load_scene(scene())
    w.step(360)                                  # the ball has landed and rested too
    assert not w.state.awake[1]
    assert not w.state.awake[2]
    w.state.pos[2] = [0.0, 0.0, 0.6]            # lift the (sleeping) ball above the box
    w.wake(2)
    w.step(100)                                  # it lands after ~0.27 s
    assert w.state.awake[1]                      # woken by the ball landing on it
    assert w.body("ball").position[2] > 0.2 + 0.05 - 0.006   # resting on the box, not in it


def test_a_command_wakes_a_sleeping_body():
    w = load_scene(scene())
    w.step(180)
    assert not w.state.awake[1]
    w.apply_impulse("box", [0.5, 0, 0])
    w.step()
    assert w.state.awake[1] and w.body("box").velocity[0] > 0.1


def test_sleep_off_keeps_everything_awake():
    w = load_scene({**scene(), "effects": {"contacts": {"sleep": False}}})
    w.step(240)
    assert w.state.awake.all()
