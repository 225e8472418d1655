"""The World's Python API (INTERFACE.md): the pipeline, commands, determinism.

Commands are held forces and torques (until replaced; zero clears) and
one-shot impulses; a refused command raises CommandError and leaves no trace.
"""
import math

import numpy as np
import pytest

from physics_core import CommandError, NonFiniteStateError, load_scene
from physics_scenes import box, g_of, oscillator, scene, sphere, state_hash

DT = 1.0 / 240.0
FORCE_STAGES = ("gravity", "gravitation", "drag", "buoyancy", "springs")


def pipeline_scene(effects=(), gravity=None):
    """Two bodies with per-body drag data, and a spring only if asked for."""
    top = {"effects": {e: {} for e in effects if e not in ("springs", "gravity")}}
    if "gravity" in effects or gravity is not None:
        top["gravity"] = gravity if gravity is not None else "earth"
    if "buoyancy" in effects:
        top["effects"]["buoyancy"] = {"fluid_density": 1000.0}
    if "springs" in effects:
        top["springs"] = [{"a": "ball", "b": "crate", "stiffness": 10.0, "rest_length": 1.0}]
    return scene(sphere(drag={"cd": 0.5, "area": 0.03, "b": 0.1}),
                 box("crate", mass=2.0, position=(1, 0, 0)), **top)


# ---- the pipeline lists only declared effects --------------------------------

@pytest.mark.parametrize("effects", [
    (), ("gravity",), ("drag",), ("gravitation",), ("gravity", "buoyancy"), ("springs",),
    ("gravity", "drag", "springs"), ("gravity", "gravitation", "drag", "buoyancy", "springs"),
])
def test_stage_names_list_only_declared_effects(effects):
    """Promise: an effect the scene does not declare is not in the step at all
    (not a stage, never timed), in the fixed order gravity, gravitation, drag,
    buoyancy, springs."""
    world = load_scene(pipeline_scene(effects))
    expected = [f"force:{e}" for e in FORCE_STAGES if e in effects]
    assert [n for n in world.stage_names if n.startswith("force:")] == expected
    assert world.stage_names[:2] == ["impulses", "integrate"] and world.stage_names[-1] == "finite"
    world.step(3)
    timed = {k[len("force:"):] for k in world.profile if k.startswith("force:")}
    assert timed == set(effects)


def test_zero_gravity_vector_is_no_gravity_stage():
    assert "force:gravity" not in load_scene(pipeline_scene(gravity=[0.0, 0.0, 0.0])).stage_names


def test_per_body_drag_data_without_the_drag_effect_changes_nothing():
    """Drag numbers on a body are parameters, not an effect: without `effects.drag`
    the body falls exactly as in vacuum (bit for bit the same as a body without them)."""
    plain = scene(sphere(), gravity="earth")
    with_data = scene(sphere(drag={"cd": 1.0, "area": 1.0, "b": 5.0}), gravity="earth")
    a, b = load_scene(plain), load_scene(with_data)
    a.step(100)
    b.step(100)
    assert state_hash(a) == state_hash(b)


def test_profile_times_each_declared_stage():
    world = load_scene(pipeline_scene(("gravity", "drag")))
    world.step(5)
    for name in ("integrate", "force:gravity", "force:drag", "finite", "step"):
        assert world.profile[name] > 0.0
    assert set(world.last_step_profile) >= {"integrate", "force:gravity", "force:drag", "finite"}


def test_last_step_profile_is_the_last_calls_share_of_the_totals():
    """last_step_profile × the call's steps is what that call added to the
    cumulative profile, stage by stage (to rounding of the cycle-to-seconds
    product): the first call from zero, the second from the first's totals,
    including a contact scene's stages."""
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True}
    world = load_scene(scene(ground, sphere(position=(0.0, 0.0, 0.2)), gravity="earth",
                             effects={"contacts": {}}))
    world.step(3)
    first, last = world.profile, world.last_step_profile
    assert set(last) >= {"integrate", "collide", "solve", "finite"}
    for stage, seconds in last.items():
        assert seconds > 0.0 and abs(3 * seconds - first[stage]) <= 1e-12 * first[stage]
    world.step(40)
    second, last = world.profile, world.last_step_profile
    for stage, seconds in last.items():
        added = second[stage] - first[stage]
        assert seconds > 0.0 and abs(40 * seconds - added) <= 1e-9 * second[stage]


# ---- held forces and torques, one-shot impulses -------------------------------

def test_force_is_held_until_replaced_and_zero_clears_it():
    """F = m a with the force held step after step: v = F t / m; a new force replaces
    (not adds to) the old; a zero force clears it and v stays constant (1e-12)."""
    world = load_scene(scene(sphere(mass=2.0)))
    world.apply_force("ball", [4.0, 0.0, 0.0])
    world.step(240)
    assert world.body("ball").velocity[0] == pytest.approx(2.0, abs=1e-12)
    world.apply_force("ball", [0.0, -2.0, 0.0])       # replaces the 4 N along x
    world.step(240)
    assert world.body("ball").velocity == pytest.approx([2.0, -1.0, 0.0], abs=1e-12)
    world.apply_force("ball", [0.0, 0.0, 0.0])
    v = world.body("ball").velocity
    world.step(240)
    assert np.array_equal(world.body("ball").velocity, v)


def test_a_force_held_again_after_clear_loads_pushes_again():
    """Regression guard for the step's cached load flags (world.step writes
    them only when has_user_force / has_user_torque change): a force, then
    clear_loads, then the same force again gives v = F t / m over the last
    second only, and the same for a torque about a sphere's axis."""
    world = load_scene(scene(sphere(mass=2.0, radius=0.5)))        # I = 0.2 kg m²
    world.step(1)                     # the flags written once with nothing held
    for _ in range(2):
        world.apply_force("ball", [4.0, 0.0, 0.0])
        world.apply_torque("ball", [0.0, 0.0, 0.2])
        world.step(240)
        world.clear_loads()
        world.step(240)
    assert world.body("ball").velocity[0] == pytest.approx(4.0, abs=1e-12)
    assert world.body("ball").angular_velocity[2] == pytest.approx(2.0, abs=1e-12)


def test_force_is_in_world_axes_whatever_the_body_orientation():
    world = load_scene(scene(box(orientation=[0.0, 0.0, 0.0, 1.0], mass=1.0)))   # turned 180° about z
    world.apply_force("box", [1.0, 0.0, 0.0])
    world.step(240)
    assert world.body("box").velocity == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)


def test_torque_is_held_until_replaced_and_zero_clears_it():
    world = load_scene(scene(sphere(mass=2.0, radius=0.5)))        # I = 2/5 m r² = 0.2
    world.apply_torque("ball", [0.0, 0.0, 0.2])
    world.step(240)
    assert world.body("ball").angular_velocity == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)
    world.apply_torque("ball", [0.0, 0.0, 0.0])
    world.step(240)
    assert world.body("ball").angular_velocity == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)


def test_impulse_is_applied_once_at_the_next_step():
    """Δv = J/m at the next step only; two impulses before a step add up."""
    world = load_scene(scene(sphere(mass=0.5)))
    world.apply_impulse("ball", [1.0, 0.0, 0.0])
    world.apply_impulse("ball", [0.0, 0.5, 0.0])
    assert np.array_equal(world.body("ball").velocity, np.zeros(3))
    world.step()
    assert world.body("ball").velocity == pytest.approx([2.0, 1.0, 0.0], abs=1e-15)
    world.step(100)
    assert world.body("ball").velocity == pytest.approx([2.0, 1.0, 0.0], abs=1e-15)
    world.apply_impulse("ball", [0.0, 0.0, 0.25])      # a later impulse brings only itself
    world.step()
    assert world.body("ball").velocity == pytest.approx([2.0, 1.0, 0.5], abs=1e-15)


def test_angular_impulse_is_applied_once():
    world = load_scene(scene(sphere(mass=2.0, radius=0.5)))
    world.apply_angular_impulse("ball", [0.0, 0.1, 0.0])
    world.step(50)
    assert world.body("ball").angular_velocity == pytest.approx([0.0, 0.5, 0.0], abs=1e-15)


def test_command_wakes_nothing_else_and_moves_only_its_body():
    world = load_scene(scene(sphere("a"), sphere("b", position=(2, 0, 0))))
    world.apply_force("a", [1.0, 0.0, 0.0])
    world.step(10)
    assert np.array_equal(world.body("b").velocity, np.zeros(3))


# ---- refused commands ------------------------------------------------------------

BAD_NUMBERS = [[math.nan, 0.0, 0.0], [0.0, math.inf, 0.0], [0.0, 0.0, -math.inf]]


def _all_commands(world, good, bad, where):
    """Each command with the bad vector in the given argument position."""
    vec, point = (bad, None) if where == "vector" else (good, bad)
    calls = [lambda: world.apply_impulse("ball", vec, point=point),
             lambda: world.apply_force("ball", vec, point=point)]
    if where == "vector":
        calls += [lambda: world.apply_torque("ball", vec), lambda: world.apply_angular_impulse("ball", vec)]
    return calls


@pytest.mark.parametrize("bad", BAD_NUMBERS, ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("where", ["vector", "point"])
def test_non_finite_command_is_refused_and_never_enters_the_state(bad, where):
    """NaN or inf anywhere in a command (the vector or its point) raises CommandError,
    and the world then steps bit for bit like one that never saw the command."""
    world = load_scene(scene(sphere(velocity=[0.1, 0.0, 0.0]), gravity="earth"))
    twin = load_scene(scene(sphere(velocity=[0.1, 0.0, 0.0]), gravity="earth"))
    for command in _all_commands(world, [1.0, 2.0, 3.0], bad, where):
        with pytest.raises(CommandError, match="finite"):
            command()
    s = world.state
    assert not (s.user_force.any() or s.user_torque.any() or s.impulse.any() or s.angular_impulse.any())
    world.step(10)
    twin.step(10)
    assert state_hash(world) == state_hash(twin)


@pytest.mark.parametrize("value", [[1.0, 2.0], "up", None, [[1.0, 2.0, 3.0]] * 2])
def test_malformed_vector_is_refused(value):
    world = load_scene(scene(sphere()))
    with pytest.raises(CommandError, match="3 numbers"):
        world.apply_force("ball", value)


def test_unknown_and_static_bodies_are_refused_by_name():
    world = load_scene(scene(sphere(), {"name": "ground", "shape": {"type": "plane"}}))
    with pytest.raises(CommandError, match="unknown body 'bal'.*ball"):
        world.apply_force("bal", [1.0, 0.0, 0.0])
    with pytest.raises(CommandError, match="static"):
        world.apply_impulse("ground", [1.0, 0.0, 0.0])
    with pytest.raises(KeyError, match="bal"):
        world.body("bal")


def test_non_finite_state_is_reported_with_the_body_name():
    """A command within the bounds can still take a state beyond them (1e9 N on
    a microgram: 1e18 m/s² past STATE_LIMIT in one step): the step reports the
    body instead of carrying it forward."""
    world = load_scene(scene(sphere("feather", mass=1e-9), sphere("other", position=(1, 0, 0))))
    world.apply_force("feather", [1e9, 0.0, 0.0])
    with pytest.raises(NonFiniteStateError, match="feather") as err:
        world.step()
    assert "other" not in str(err.value)
    assert err.value.stage == "integrate" and err.value.bodies == (0,)


def test_loads_beyond_the_command_limits_are_refused_before_the_state_changes():
    """Regression: a 1e300 N force or 1e200 N·s impulse used to reach the
    broad phase as a position of 1e297 m and fail there with a numpy error."""
    world = load_scene(scene(sphere("ball"), sphere("other", position=(1, 0, 0))))
    for apply, value in ((world.apply_force, 1e300), (world.apply_impulse, 1e200), (world.apply_torque, 1e300),
                         (world.apply_angular_impulse, 1e300)):
        with pytest.raises(CommandError, match="beyond the limit"):
            apply("ball", [value, 0.0, 0.0])
    assert not world.state.has_pending_impulse and not world.state.user_force.any()
    world.step()


def test_explicit_euler_cannot_hold_a_stiff_undamped_spring():
    """Explicit Euler multiplies an undamped oscillation by √(1 + ω²h²) every sub-step,
    so even with the automatic sub-steps a k = 1e6 spring grows until the finite check
    stops it (documented in effects/springs.py)."""
    world = load_scene(oscillator(1e6, 1.0, x0=0.01, integrator="explicit_euler"))
    with pytest.raises(NonFiniteStateError, match="bob"):
        with np.errstate(all="ignore"):
            world.step(2400)
    assert world.time < 10.0


# ---- time, energy, determinism, reset --------------------------------------------

def test_time_is_step_count_times_dt():
    world = load_scene(scene(sphere(), dt=0.01))
    world.step(0)
    assert world.time == 0.0
    world.step(1000)
    assert world.step_index == 1000 and world.time == 1000 * 0.01


def test_energy_is_kinetic_plus_gravity_potential():
    """E = ½ m v² + ½ ω·I ω − m g·x; a Verlet projectile keeps it to 1e-10 J."""
    world = load_scene(scene(box(mass=2.0, velocity=[3.0, 0.0, 4.0], angular_velocity=[0.0, 0.0, 1.0]),
                             gravity="earth", integrator="velocity_verlet"))
    I_z = 2.0 / 3.0 * (0.5 ** 2 + 0.3 ** 2)
    assert world.energy() == pytest.approx(0.5 * 2.0 * 25.0 + 0.5 * I_z, rel=1e-14)
    world.step(240)
    z = world.body("box").position[2]
    assert world.kinetic_energy() - 2.0 * g_of("earth") * (-z) == pytest.approx(world.energy(), rel=1e-14)
    assert world.energy() == pytest.approx(25.0 + 0.5 * I_z, abs=1e-10)


def test_forces_can_be_read_before_the_first_step():
    world = load_scene(scene(sphere(mass=2.0), gravity="moon"))
    s = world.state
    F, T = world.forces(s.pos, s.quat, s.vel, s.omega)
    assert F[0] == pytest.approx([0.0, 0.0, -2.0 * g_of("moon")], rel=1e-12)
    assert np.array_equal(T, np.zeros((1, 3)))


def _busy_scene():
    """Every force effect at once, with rotation: a stress test for determinism."""
    return scene(
        sphere("a", mass=1.0, velocity=[0.3, 0.1, 0.0], drag={"cd": 0.5}),
        box("b", mass=2.0, position=(1.0, 0.2, -0.05), angular_velocity=[0.2, 1.0, 3.0]),
        sphere("c", mass=0.7, radius=0.2, position=(-1.0, 0.5, 0.5)),
        gravity="earth", integrator="velocity_verlet",
        effects={"gravitation": {"G": 0.1}, "drag": {"model": "reynolds"},
                 "buoyancy": {"fluid_density": 1000.0, "linear_damping": 5.0, "angular_damping": 0.5}},
        springs=[{"a": "a", "b": "b", "stiffness": 300.0, "rest_length": 0.8, "damping": 1.0,
                  "point_b": [0.3, 0.1, 0.0]},
                 {"a": "c", "b": "world", "stiffness": 50.0, "point_b": [-1.0, 0.0, 1.0]}])


def _run_busy(nudge=0.0):
    world = load_scene(_busy_scene())
    world.step(100)
    world.apply_force("b", [0.0, 1.0 + nudge, 0.0], point=[1.0, 0.0, 0.0])
    world.apply_impulse("a", [0.1, 0.0, 0.0], point=[0.0, 0.05, 0.0])
    world.step(200)
    return world


def test_two_identical_runs_are_bit_identical():
    """Determinism (Box2D-style): same scene and commands → same state hash; a
    one-ulp change of one command changes it, so the hash does see the state."""
    a, b = _run_busy(), _run_busy()
    assert state_hash(a) == state_hash(b)
    assert state_hash(_run_busy(nudge=np.spacing(1.0))) != state_hash(a)


def test_reset_returns_to_the_initial_state_and_replays_identically():
    first = _run_busy()
    h = state_hash(first)
    first.reset()
    assert first.time == 0.0 and first.step_index == 0
    assert np.array_equal(first.state.pos, first.model.initial["pos"])
    assert not first.state.user_force.any()
    first.step(100)
    first.apply_force("b", [0.0, 1.0, 0.0], point=[1.0, 0.0, 0.0])
    first.apply_impulse("a", [0.1, 0.0, 0.0], point=[0.0, 0.05, 0.0])
    first.step(200)
    assert state_hash(first) == h


def test_set_body_state_moves_a_static_box_and_a_ball_dropped_there_rests_on_it():
    import warnings

    scene = {"dt": 0.005, "gravity": "earth", "effects": {"contacts": {}}, "bodies": [
        {"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}, "static": True},
        {"name": "table", "shape": {"type": "box", "half_extents": [0.5, 0.5, 0.05]}, "static": True,
         "position": [0, 0, 0.5]},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "position": [3, 0, 1.5]}]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the fallback friction pair
        world = load_scene(scene)
    world.set_body_state("table", position=[3, 0, 0.5])
    world.step(600)
    # resting on the table top (z = 0.55) within the contact slop, not on the ground
    assert abs(world.body("ball").position[2] - 0.65) < 0.01


def test_set_body_state_refuses_what_it_cannot_do_and_changes_nothing():
    world = load_scene({"dt": 0.01, "bodies": [
        {"name": "ground", "shape": {"type": "plane"}, "static": True},
        {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0}]})
    before = world.body("ball").position
    for kwargs, match in (
        (dict(name="ball", position=[0, 0, 1], orientation=[2.0, 0, 0, 0]), "unit quaternion"),
        (dict(name="ball", position=[0, 0, float("nan")]), "finite"),
        (dict(name="ground", velocity=[1.0, 0, 0]), "static"),
        (dict(name="ground", position=[0, 0, 1.0]), "plane"),
        (dict(name="nobody", position=[0, 0, 1.0]), "unknown body"),
    ):
        with pytest.raises(CommandError, match=match):
            world.set_body_state(**kwargs)
    assert np.array_equal(world.body("ball").position, before)
    world.set_body_state("ball", position=[1.0, 2.0, 3.0], velocity=[0, 0, 1.0])
    assert world.body("ball").position.tolist() == [1.0, 2.0, 3.0]
    assert world.body("ball").velocity.tolist() == [0.0, 0.0, 1.0]
