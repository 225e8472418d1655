"""world.step passes its arrays to the compiled loop as one packed object
(physics_core/step_inputs.py), packed again only when an array in it is
replaced. Each test replaces something between steps the way a user or the
node does and checks that the next step moves the new arrays, by a closed
form or against a World that never held the old ones."""
import numpy as np

from physics_core import load_scene
from physics_scenes import g_of, scene, sphere

DT = 1.0 / 240.0


def _free_ball(**extra):
    return load_scene(scene(sphere("ball", velocity=[1.0, 0.0, 0.0]), dt=DT, **extra))


def _ball_on_ground(**contacts):
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True}
    return load_scene(scene(ground, sphere("ball", position=(0.0, 0.0, 0.5)), dt=DT,
                            gravity="earth", effects={"contacts": contacts}))


def test_a_velocity_array_assigned_between_steps_is_the_one_the_next_step_moves():
    """Regression guard for stale packed inputs: after `state.vel = new`,
    x(t) = x0 + v t with the new v (no force: exact in float64 to rounding)."""
    world = _free_ball()
    world.step(3)
    x0 = world.state.pos[0, 0]
    new_vel = np.array([[0.0, 2.0, 0.0]])
    world.state.vel = new_vel
    world.step(10)
    assert world.state.vel is new_vel
    np.testing.assert_allclose(world.state.pos[0], [x0, 2.0 * 10 * DT, 0.0], rtol=0, atol=1e-12)


def test_a_position_array_assigned_between_steps_is_the_one_the_next_step_moves():
    world = _free_ball()
    world.step(1)
    world.state.pos = np.array([[5.0, 0.0, 0.0]])
    world.step(4)
    np.testing.assert_allclose(world.state.pos[0], [5.0 + 4 * DT, 0.0, 0.0], rtol=0, atol=1e-12)


def test_inputs_are_packed_once_while_no_array_is_replaced():
    world = _ball_on_ground()
    world.step(1)
    packed = world._packed[1]
    world.apply_force("ball", [1.0, 0.0, 0.0])     # held loads are written in place
    world.step(5)
    assert world._packed[1] is packed


def test_reset_after_contacts_steps_like_a_new_world_bit_for_bit():
    """reset() gives the contact system new warm cache, event log and sleep
    state: the steps after it must use those, not the ones before."""
    world, fresh = _ball_on_ground(), _ball_on_ground()
    world.step(200)                   # the ball has landed: warm starts and events exist
    world.reset()
    world.step(150)
    fresh.step(150)
    for name in ("pos", "quat", "vel", "omega"):
        assert np.array_equal(getattr(world.state, name), getattr(fresh.state, name)), name
    assert len(world.contacts) == len(fresh.contacts)


def test_a_body_added_after_steps_falls_by_half_g_t_squared():
    world = _ball_on_ground()
    world.step(10)
    world.add_body(sphere("late", position=(3.0, 0.0, 5.0)))
    world.step(24)
    z = world.state.pos[world.model.index["late"], 2]
    # semi-implicit Euler: z = z0 - g dt² n(n+1)/2 (COURSE.md 2 for g)
    g = g_of("earth")
    expected = 5.0 - g * DT ** 2 * 24 * 25 / 2
    assert abs(z - expected) < 1e-9, (z, expected)


def test_a_sleeping_body_woken_from_python_falls_again():
    """Waking replaces the solver's mass arrays (World.refresh_awake): the next
    step must integrate the body with its real inverse mass, not the zero of
    sleep: z = -g dt² n(n+1)/2 after n semi-implicit Euler steps."""
    world = load_scene(scene(sphere("ball"), dt=DT, gravity="earth"))
    world.state.awake[0] = False
    world.refresh_awake()
    world.step(5)
    assert world.state.pos[0, 2] == 0.0
    world.wake(0)
    world.step(6)
    np.testing.assert_allclose(world.state.pos[0, 2], -g_of("earth") * DT ** 2 * 6 * 7 / 2,
                               rtol=1e-12, atol=0)


def test_world_step_calls_the_compiled_loop_directly_and_steps_as_the_dispatcher_does():
    """world.step calls run_steps' compiled function for the packed inputs'
    types (step_inputs.compiled_entry), not numba's dispatcher: 200 steps
    of a ball landing on the ground (impact, bounce, resting contact) give
    the same bits as a World stepped through the dispatcher."""
    from physics_core.step_loop import run_steps
    world, through_dispatcher = _ball_on_ground(), _ball_on_ground()
    world.step(200)
    other = through_dispatcher
    done, failed = run_steps(other._inputs(), 200, other.substeps, other.model.dt, other._code)
    assert (done, failed) == (200, -1)
    assert world._packed[2] is not run_steps
    for name in ("pos", "quat", "vel", "omega"):
        np.testing.assert_array_equal(getattr(world.state, name), getattr(other.state, name))
    assert world.state.pos[0, 2] < 0.5               # it fell: the steps ran


def test_compiled_entry_falls_back_to_the_callable_without_numba_overloads():
    from physics_core.step_inputs import compiled_entry

    def plain(a, b):
        return a + b
    assert compiled_entry(plain, (1, 2.0)) is plain


def test_substeps_set_between_steps_is_the_count_the_next_step_takes():
    """Regression guard for a step call cached with its substep count: after
    `world.substeps = 4`, one step of semi-implicit Euler from rest under g
    falls g dt² (k + 1) / (2 k) (the sum of k substeps of h = dt / k:
    g h² (1 + 2 + … + k)), not g dt² as with the one substep before."""
    world = load_scene(scene(sphere("ball"), dt=DT, gravity="earth"))
    g = g_of("earth")
    world.step(1)
    assert abs(-world.state.pos[0, 2] - g * DT * DT) < 1e-15
    world.state.vel[:] = 0.0
    world.state.pos[:] = 0.0
    world.substeps = 4
    world.step(1)
    assert abs(-world.state.pos[0, 2] - g * DT * DT * 5.0 / 8.0) < 1e-15
    assert abs(-world.state.vel[0, 2] - g * DT) < 1e-15
