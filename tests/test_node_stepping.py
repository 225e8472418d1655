"""The step boundary without ROS: command checks, the applier's frames and
hold rules, timeouts, and the real-time pacer."""

import numpy as np
import pytest

from physics_core import load_scene
from physics_node.commands import (
    IMPULSE,
    NON_FINITE,
    STATIC_BODY,
    UNKNOWN_BODY,
    UNKNOWN_FRAME,
    WRENCH,
    Command,
    check,
)
from physics_node.node import TICK_BUDGET_S
from physics_node.pacing import FREE_RUN_CHECK_S, StepPacer
from physics_node.stepping import Stepper

SCENE = {
    "dt": 0.01,
    "integrator": "semi_implicit_euler",
    "bodies": [
        {"name": "floor", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}, "static": True},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 2.0, "position": [0, 0, 1]},
        {
            "name": "spinner",
            "shape": {"type": "box", "half_extents": [0.2, 0.1, 0.1]},
            "mass": 1.0,
            "position": [1, 0, 1],
            "angular_velocity": [0, 0, 3.0],
        },
    ],
}


def world():
    scene = dict(SCENE)
    scene["bodies"] = [dict(b) for b in SCENE["bodies"]]
    return load_scene(scene)


def cmd(kind, body, force, torque=(0, 0, 0), frame="world"):
    return Command(kind, body, frame, np.array(force, dtype=float), np.array(torque, dtype=float))


def test_check_names_the_reason_for_each_bad_command():
    model = world().model
    assert check(cmd(WRENCH, "ball", [1, 0, 0]), model) is None
    assert check(cmd(WRENCH, "ball", [1, 0, 0], frame=""), model) is None
    assert check(cmd(WRENCH, "ball", [1, 0, 0], frame="ball"), model) is None
    assert check(cmd(WRENCH, "nobody", [1, 0, 0]), model) == UNKNOWN_BODY
    assert check(cmd(WRENCH, "ball", [np.nan, 0, 0]), model) == NON_FINITE
    assert check(cmd(IMPULSE, "ball", [0, 0, 0], [0, -np.inf, 0]), model) == NON_FINITE
    assert check(cmd(WRENCH, "ball", [1, 0, 0], frame="spinner"), model) == UNKNOWN_FRAME
    assert check(cmd(WRENCH, "floor", [1, 0, 0]), model) == STATIC_BODY


def test_commands_apply_in_arrival_order_at_the_boundary():
    w = world()
    s = Stepper(w)
    s.submit(cmd(WRENCH, "ball", [4, 0, 0]))
    s.submit(cmd(WRENCH, "ball", [0, 2, 0]))  # replaces the first
    b = s.advance()
    assert b.step == 0 and len(b.applied) == 2 and w.step_index == 1
    assert w.state.vel[1] == pytest.approx([0, 1.0 * 0.01, 0])


def test_zero_wrench_lets_go():
    w = world()
    s = Stepper(w)
    s.submit(cmd(WRENCH, "ball", [2, 0, 0]))
    s.advance()
    s.submit(cmd(WRENCH, "ball", [0, 0, 0]))
    s.advance()
    v = w.state.vel[1].copy()
    s.advance()
    assert np.array_equal(w.state.vel[1], v)


def test_impulse_applies_once():
    w = world()
    s = Stepper(w)
    s.submit(cmd(IMPULSE, "ball", [0, 0, 3.0]))
    s.advance()
    s.advance()
    assert w.state.vel[1] == pytest.approx([0, 0, 1.5])


def test_body_axis_wrench_turns_with_the_body():
    w = world()
    s = Stepper(w)
    s.submit(cmd(WRENCH, "spinner", [1.0, 0, 0], frame="spinner"))
    for _ in range(50):
        s.advance()
    # The spinner turned 1.5 rad; a thruster along its own x pushed along a
    # turning direction, so the velocity is not along world x.
    v = w.state.vel[2]
    assert abs(v[1]) > 0.05
    # The same force held in world axes pushes along x only.
    w2 = world()
    s2 = Stepper(w2)
    s2.submit(cmd(WRENCH, "spinner", [1.0, 0, 0]))
    for _ in range(50):
        s2.advance()
    assert w2.state.vel[2][1] == 0.0


def test_wrench_times_out_in_sim_time_and_the_release_is_reported():
    w = world()
    s = Stepper(w, command_timeout=0.05)
    s.submit(cmd(WRENCH, "ball", [2, 0, 0]))
    released = []
    for _ in range(10):
        b = s.advance()
        released += [(b.step, c.body) for c in b.applied if not c.force.any()]
    assert released == [(5, "ball")]


def test_reset_forgets_queue_and_held_wrenches():
    w = world()
    s = Stepper(w)
    s.submit(cmd(WRENCH, "spinner", [1, 0, 0], frame="spinner"))
    s.advance()
    s.submit(cmd(IMPULSE, "ball", [1, 0, 0]))
    assert len(s.reset()) == 1  # the discarded commands, for the node to count
    s.advance()
    assert w.step_index == 1 and not w.state.vel[1:].any()


def test_refused_command_is_reported_not_raised():
    w = world()
    s = Stepper(w)
    s.submit(cmd(WRENCH, "floor", [1, 0, 0]))
    b = s.advance()
    assert not b.applied and len(b.rejected) == 1


def test_pacer_follows_wall_time_times_rtf():
    p = StepPacer(dt=0.01, real_time_factor=2.0)
    p.restart(100.0)
    assert p.due(100.0) == 0
    assert p.due(100.05) == 10
    p.took(10)
    assert p.due(100.06) == 2


def test_pacer_drops_a_large_backlog():
    p = StepPacer(dt=0.01, real_time_factor=1.0, max_lag=0.25)
    p.restart(0.0)
    assert p.due(5.0) == 1


def test_pacer_unlimited_at_rtf_zero():
    p = StepPacer(dt=0.01, real_time_factor=0.0)
    # the timer only starts the free run: not due again when a step budget ends
    assert p.due(123.0) is None and p.tick_period() == FREE_RUN_CHECK_S > TICK_BUDGET_S
    assert StepPacer(0.01, 1.0).tick_period() == pytest.approx(0.01)
    assert StepPacer(0.001, 100.0).tick_period() == pytest.approx(0.002)
    assert StepPacer(0.005, 1.0).tick_period() == pytest.approx(0.005)
