"""integrate_substep (physics_core/integration.py), the integrate stage callable
from compiled code, against the integrate stage as the World ran it before.

tests/frozen_integrate is a copy of the Python integrators and force effects
of commit 76bcc0d (a Python wrapper per integrator calling World.forces, then
compiled update loops), with `System`, that commit's World reduced to its
integrate stage: the reference. From the same start, over 200 substeps,
four paths must give the reference's bits in pos, quat, vel and omega
(COURSE.md 4):

    World.step (its compiled loop, step_loop.py, calls integrate_substep);
    the Python integrators (integrators.INTEGRATORS, wrappers over it) on a World;
    integrate_substep called from Python, substep after substep;
    integrate_substep called from a small @njit loop.

The forces (`integration.forces` and World.forces against the reference's)
must agree bit for bit as well. The scenes mix spheres, a cube, a spinning slab and needle
(asymmetric: the splitting of free_rotation.py), a static body and a
sleeping one (zero inverse mass), under each effect alone and all at once,
with held forces at points and held torques, with spin and without
(the rotational half skipped), for all four integrators; and random scenes
(test_integration_kernels' strategy) up to the point where they blow up.
"""
import math
import os

import numpy as np

from physics_core.command_limits import STATE_LIMIT
import pytest
from hypothesis import HealthCheck, given, settings
from numba import njit, typeof

import frozen_integrate as frozen
from physics_core import integration, load_scene
from physics_core.effects import MODULES, declared_effects
from physics_core.integrators import INTEGRATORS as WRAPPERS
from physics_core.errors import NonFiniteStateError
from physics_core.integration import (INTEGRATOR_CODES, can_make_torque, integrate_substep, integration_data,
                                      integration_profile, integration_work)
from physics_scenes import INTEGRATORS, box, scene, sphere
from test_integration_kernels import _prepare, scenes

SUBSTEPS = 200
FIELDS = ("pos", "quat", "vel", "omega")
EXAMPLES = int(os.environ.get("LOOP_EXAMPLES", "40"))


# ---- the scenes ---------------------------------------------------------------------

SLAB_AT = (-1.0, 0.5, 0.05)


def _bodies(spin):
    w = (lambda *v: list(v)) if spin else (lambda *v: [0.0, 0.0, 0.0])
    c, s = math.cos(0.3), math.sin(0.3)
    return [sphere("ball", radius=0.2, mass=2.0, position=(0.0, 0.0, 0.1), velocity=[1.0, 0.5, -0.2],
                   angular_velocity=w(0.0, 3.0, 1.0), drag={"cd": 0.5}),
            box("cube", half_extents=(0.2, 0.2, 0.2), mass=1.5, position=(1.0, 0.2, -0.1),
                velocity=[0.0, -0.4, 0.3], angular_velocity=w(0.3, 0.0, 2.0)),
            box("slab", half_extents=(0.5, 0.05, 0.2), mass=0.8, position=SLAB_AT,
                orientation=[c, s, 0.0, 0.0], angular_velocity=w(0.1, 4.0, 0.2)),
            box("needle", half_extents=(0.6, 0.02, 0.01), mass=0.3, position=(0.3, -1.0, 0.3),
                velocity=[0.2, 0.0, 0.0], angular_velocity=w(0.5, 0.2, 6.0), drag={"b": 0.3}),
            sphere("sleeper", radius=0.15, mass=1.0, position=(2.0, 0.0, -0.5)),
            box("floor", half_extents=(3.0, 3.0, 0.1), position=(0.0, 0.0, -3.0), static=True)]


SPRINGS = [{"a": "ball", "b": "slab", "point_b": [0.3, 0.0, 0.1], "stiffness": 30.0, "rest_length": 0.5,
            "damping": 0.4},
           {"a": "needle", "b": "world", "point_a": [0.5, 0.0, 0.0], "point_b": [0.3, -1.0, 1.0],
            "stiffness": 10.0, "rest_length": 0.2},
           {"a": "cube", "b": "ball", "stiffness": 5.0, "rest_length": 1.5}]

EFFECTS = {
    "none": {},
    "gravity": {"gravity": "earth"},
    "gravitation": {"effects": {"gravitation": {"G": 0.5, "softening": 0.01}}},
    "drag_linear": {"effects": {"drag": {"model": "linear", "b": 0.7}}},
    "drag_quadratic": {"effects": {"drag": {"model": "quadratic", "fluid_density": 5.0}}},
    "drag_reynolds": {"effects": {"drag": {"model": "reynolds", "reynolds_threshold": 3e4}}},
    "buoyancy": {"gravity": "earth", "effects": {"buoyancy": {"fluid_density": 900.0, "linear_damping": 2.0,
                                                              "angular_damping": 0.002, "cells": 3}}},
    "springs": {"springs": SPRINGS},
    "all": {"gravity": "earth", "springs": SPRINGS,
            "effects": {"gravitation": {"G": 0.5, "softening": 0.01}, "drag": {"model": "quadratic"},
                        "buoyancy": {"fluid_density": 900.0, "linear_damping": 2.0, "cells": 2}}},
}
LOADS = ("held", "free", "still")    # held forces and torques, spin; spin only; neither


def _scene(effects, loads, integrator):
    return scene(*_bodies(loads != "still"), integrator=integrator, **EFFECTS[effects])


def _load(world, loads):
    """The held loads (a force at a point of the slab and a torque on it, so the
    order of the torque's terms shows; a force at the ball's centre, a torque
    on the cube), then the sleeper put to sleep."""
    if loads == "held":
        world.apply_force("slab", [3.0, -1.0, 2.0], point=np.add(SLAB_AT, [0.3, 0.02, 0.1]))
        world.apply_torque("slab", [-0.03, 0.05, 0.01])
        world.apply_force("ball", [0.0, 1.0, 0.0])
        world.apply_torque("cube", [0.2, 0.0, -0.1])
    world.state.awake[world.model.index["sleeper"]] = False
    world.refresh_awake()
    return world


# ---- the paths ------------------------------------------------------------------------

def _arrays(world):
    """Copies of the state arrays, and the rest of integrate_substep's arguments."""
    s = world.state
    state = [getattr(s, name).copy() for name in FIELDS]
    rest = (world.inv_mass[:, 0].copy(), world.inertia, world.inv_inertia.copy(), s.user_force.copy(),
            s.user_force_offset.copy(), s.user_torque.copy(), bool(s.has_user_force), bool(s.has_user_torque),
            can_make_torque(world.model))
    return state, rest


def _finite(state):
    """The engine's own test (physics_core/finite.py): a component beyond
    STATE_LIMIT counts as non-finite, as NaN and ±inf do."""
    return all((np.abs(a) <= STATE_LIMIT).all() for a in state)


def python_path(world, count):
    """integrate_substep from Python, `count` substeps or up to a non-finite state."""
    state, rest = _arrays(world)
    code, h = INTEGRATOR_CODES[world.model.integrator], world.model.dt / world.substeps
    data, work, prof = integration_data(world.model), integration_work(world.model.n), integration_profile()
    m, inertia, inv_i, uf, uo, ut, has_f, has_t, turns = rest
    for _ in range(count):
        try:
            integrate_substep(code, h, data, *state, m, inertia, inv_i, uf, uo, ut, has_f, has_t, turns, work,
                              prof)
        except ZeroDivisionError:       # an exactly zero divisor in a scene blowing up, mid-substep
            break
        if not _finite(state):
            break
    return state


@njit
def _state_finite(pos, quat, vel, omega):
    for a in (pos, vel, omega):
        for x in a.ravel():
            if not abs(x) <= STATE_LIMIT:      # the engine's test, finite.py
                return False
    for x in quat.ravel():
        if not abs(x) <= STATE_LIMIT:
            return False
    return True


@njit
def _loop(count, code, h, data, pos, quat, vel, omega, inv_mass, inertia, inv_inertia, user_force,
          user_force_offset, user_torque, has_user_force, has_user_torque, model_torque, work, prof):
    """The compiled loop the World's step will become, integrate stage only."""
    for _ in range(count):
        integrate_substep(code, h, data, pos, quat, vel, omega, inv_mass, inertia, inv_inertia, user_force,
                          user_force_offset, user_torque, has_user_force, has_user_torque, model_torque,
                          work, prof)
        if not _state_finite(pos, quat, vel, omega):
            break


def compiled_path(world, count):
    """integrate_substep from an @njit loop."""
    state, rest = _arrays(world)
    code, h = INTEGRATOR_CODES[world.model.integrator], world.model.dt / world.substeps
    try:
        _loop(count, code, h, integration_data(world.model), *state, *rest, integration_work(world.model.n),
              integration_profile())
    except ZeroDivisionError:
        pass
    return state


def frozen_path(world, count):
    """The reference: commit 76bcc0d's integrate stage on copies of the World's
    arrays, `count` substeps or up to a non-finite state (where the World stops)."""
    system = frozen.System(world)
    h = world.model.dt / world.substeps
    for _ in range(count):
        try:
            system.substep(h)
        except ZeroDivisionError:
            break
        if not _finite([getattr(system.state, name) for name in FIELDS]):
            break
    return [getattr(system.state, name) for name in FIELDS]


def wrapper_path(world, count):
    """The Python integrators on the World itself, substep after substep."""
    integrate, h = WRAPPERS[world.model.integrator], world.model.dt / world.substeps
    for _ in range(count):
        try:
            integrate(world, h)
        except ZeroDivisionError:
            break
        if not _finite([getattr(world.state, name) for name in FIELDS]):
            break
    return [getattr(world.state, name) for name in FIELDS]


def world_path(world, steps):
    """World.step, one step at a time; (the state, (the step it blew up at, how) or None)."""
    for k in range(steps):
        try:
            world.step()
        except (NonFiniteStateError, ZeroDivisionError) as e:
            return [getattr(world.state, name) for name in FIELDS], (k, type(e))
    return [getattr(world.state, name) for name in FIELDS], None


def _same(got, want, what):
    for name, a, b in zip(FIELDS, got, want):
        assert np.array_equal(a, b, equal_nan=True), f"{what}: {name} differs " \
            f"(max {float(np.nanmax(np.abs(a - b), initial=0.0)):.3e})"


def _forces_match(world):
    """integration.forces and World.forces against the reference's, bit for bit."""
    s = world.state
    F_ref, T_ref = frozen.System(world).forces(s.pos, s.quat, s.vel, s.omega)
    F, T = np.full_like(F_ref, np.nan), np.full_like(T_ref, np.nan)     # forces must overwrite them
    integration.forces(integration_data(world.model), s.pos, s.quat, s.vel, s.omega, s.user_force,
                       s.user_force_offset, s.user_torque, bool(s.has_user_force), bool(s.has_user_torque), F, T)
    F_world, T_world = world.forces(s.pos, s.quat, s.vel, s.omega)
    for got in ((F, T), (F_world, T_world)):
        assert np.array_equal(got[0], F_ref, equal_nan=True) and np.array_equal(got[1], T_ref, equal_nan=True)


def all_paths_agree(sc, prepare):
    """Run the five paths from the scene's start; returns the World that World.step stepped."""
    stepped, wrapped = prepare(load_scene(sc)), prepare(load_scene(sc))
    assert can_make_torque(stepped.model) == frozen.System(stepped)._model_torque
    steps = max(1, SUBSTEPS // stepped.substeps)
    count = steps * stepped.substeps
    _forces_match(stepped)
    want = frozen_path(stepped, count)
    python_state, compiled_state = python_path(stepped, count), compiled_path(stepped, count)
    got, failed = world_path(stepped, steps)
    _same(got, want, "World.step")
    _same(wrapper_path(wrapped, count), want, "the Python integrators")
    _same(python_state, want, "integrate_substep from Python")
    _same(compiled_state, want, "integrate_substep from an @njit loop")
    if failed is None:
        _forces_match(stepped)
    return stepped


# ---- the tests ------------------------------------------------------------------------

@pytest.mark.parametrize("loads", LOADS)
@pytest.mark.parametrize("effects", list(EFFECTS))
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_every_path_gives_the_frozen_states_bit_for_bit(integrator, effects, loads):
    """200 substeps of each integrator, each effect alone and all together, with
    held loads and spin, spin only, or neither: the same bits on every path."""
    world = all_paths_agree(_scene(effects, loads, integrator), lambda w: _load(w, loads))
    moved = world.state.pos[world.model.index["sleeper"]]
    assert np.array_equal(moved, [2.0, 0.0, -0.5])          # the sleeper did not move


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_substeps_inside_a_step_give_the_same_bits(integrator):
    """A scene with substeps (and the springs' own count on top) steps alike."""
    sc = dict(_scene("all", "held", integrator), substeps=3)
    world = all_paths_agree(sc, lambda w: _load(w, "held"))
    assert world.substeps >= 3


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # numpy overflow in scenes that blow up
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_random_scenes_give_the_frozen_states_bit_for_bit(case):
    """Random bodies, effects, held loads and sleepers (test_integration_kernels'
    scenes); a scene that blows up must blow up at the same step with the same bits."""
    sc, commands, sleepers = case
    if load_scene(sc).substeps > 40:
        return                                   # stiff springs on light needles: correct, only slow
    all_paths_agree(sc, lambda w: _prepare(w, commands, sleepers))


def test_every_scene_has_one_data_type():
    """Declared or not, every effect's constants have the same numba types, so one
    compiled integrate_substep serves every scene."""
    worlds = [load_scene(_scene(e, "held", "rk4")) for e in EFFECTS]
    types = {typeof(integration_data(w.model)) for w in worlds}
    assert len(types) == 1
    for w in worlds:
        for name in declared_effects(w.model):
            module = MODULES[name]
            assert typeof(module.constants(w.model)) == typeof(module.unused()), name


def test_the_profile_times_each_declared_effect():
    """The wrappers turn prof's cycles into seconds under "force:<name>" in a
    World's `_prof`; World.step puts them in world.profile."""
    world = _load(load_scene(_scene("all", "held", "velocity_verlet")), "held")
    declared = {"force:" + name for name in integration.EFFECT_NAMES}
    world.step(3)
    assert {k for k in world.profile if k.startswith("force:")} == declared
    world._prof = {}
    WRAPPERS["velocity_verlet"](world, world.model.dt)
    assert set(world._prof) == declared and min(world._prof.values()) > 0.0


@pytest.mark.parametrize("effects, timed", [("all", [1, 1, 1, 1, 1]), ("drag_linear", [0, 0, 1, 0, 0]),
                                            ("none", [0, 0, 0, 0, 0])])
def test_forces_times_only_the_declared_effects(effects, timed):
    world = _load(load_scene(_scene(effects, "held", "rk4")), "held")
    s, prof = world.state, integration_profile()
    F, T = np.zeros_like(s.pos), np.zeros_like(s.pos)
    integration.forces(integration_data(world.model), s.pos, s.quat, s.vel, s.omega, s.user_force,
                       s.user_force_offset, s.user_torque, True, True, F, T, prof)
    assert (prof > 0).astype(int).tolist() == timed


def test_an_unknown_integrator_code_is_refused():
    world = load_scene(_scene("gravity", "free", "rk4"))
    state, rest = _arrays(world)
    with pytest.raises(ValueError):
        integrate_substep(7, 0.01, integration_data(world.model), *state, *rest, integration_work(world.model.n),
                          integration_profile())
