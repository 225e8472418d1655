"""The compiled integrate stage against the numpy code it replaced.

tests/reference_integration.py is a frozen copy of the numpy integrators,
free rotation and force effects. Each example builds one random scene twice:
a World as the engine builds it (compiled kernels) and a World whose force
effects and integrator are the reference's. From the same state both
evaluate the forces and take one step, three times in a row (the compiled
World is reset to the reference's state before each step, so errors do
not compound), and must agree to 1e-12, normwise relative:

    err(Q) = max |Q_compiled − Q_reference| / scale(Q)

with scale(Q) the largest |Q| of the step's start and end state, or the
change the step's forces could make when that is larger: dt |F| / m for v,
dt |τ| / I for ω (τ is scaled by |F| times the largest lever arm, so a
torque that cancels to a residue is not held to the residue's digits), and
1 for q. Springs start stretched or compressed by at least 20 %, so their
force is not a cancellation residue either. An example stops where the
reference blows up (a random scene can be unstable at its dt; the compiled
World must then blow up too) or turns a body by more than half a turn per
sub-step (past that the orientation's sensitivity to the last bit of L is
the angle itself).

The two can differ in the last bits only where the order of a sum differs:
numpy's einsum adds three products as (p₀ + p₂) + p₁ here (AVX-512, its SIMD
horizontal sum) and np.sum over a box's cells is pairwise, where the kernels
add in index order; given the same forces the integrators agree bit for bit. Set PRINT_KERNEL_ERRORS=1 (and run with -s) to print the worst
errors met, KERNEL_EXAMPLES=n for a longer search (150 examples per test).
"""
import math
import os
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import reference_integration as ref
from physics_core import free_rotation, load_scene
from physics_core.effects import Kinematics, build_force_effects
from physics_scenes import INTEGRATORS

TOLERANCE = 1e-12
WORST = {}          # quantity -> (worst error, bit-equal runs, runs), printed with PRINT_KERNEL_ERRORS=1
EXAMPLES = int(os.environ.get("KERNEL_EXAMPLES", "150"))   # more for a longer search
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope="module", autouse=True)
def _report_worst():
    yield
    if os.environ.get("PRINT_KERNEL_ERRORS"):
        lines = [f"  {k:30s} {worst:9.2e}   {same:5d} / {runs:<5d}" for k, (worst, same, runs) in sorted(WORST.items())]
        sys.__stdout__.write("\ncompiled vs numpy: worst normwise relative error, bit-equal runs / runs\n"
                             + "\n".join(lines) + "\n")


def _check(name, got, want, scale):
    """err = max |got − want| / scale, recorded and held to TOLERANCE."""
    err = float(np.max(np.abs(got - want), initial=0.0)) / max(float(scale), 1e-300)
    worst, same, runs = WORST.get(name, (0.0, 0, 0))
    WORST[name] = (max(worst, err), same + int(np.array_equal(got, want)), runs + 1)
    assert err <= TOLERANCE, f"{name}: {err:.3e} relative (scale {scale:.3e})"


def _norm(a):
    return float(np.max(np.abs(a), initial=0.0))


# ---- random scenes ----------------------------------------------------------------

def _uniform(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


def _log_uniform(lo, hi):
    return _uniform(math.log(lo), math.log(hi)).map(math.exp)


def _vector(bound, n=3):
    return st.lists(_uniform(-bound, bound), min_size=n, max_size=n)


@st.composite
def _unit_quaternion(draw):
    q = np.array(draw(_vector(1.0, 4)))
    assume(np.linalg.norm(q) > 0.1)
    return (q / np.linalg.norm(q)).tolist()


@st.composite
def _shape(draw, kind):
    if kind == "sphere":
        return {"type": "sphere", "radius": draw(_log_uniform(0.05, 1.0))}
    if kind == "cube":
        return {"type": "box", "half_extents": [draw(_log_uniform(0.05, 1.0))] * 3}
    return {"type": "box", "half_extents": [draw(_log_uniform(0.01, 1.0)) for _ in range(3)]}


@st.composite
def _body(draw, i):
    """A sphere, a cube (isotropic), a box up to 100:1 (strongly asymmetric) or a
    static sphere or box; random mass, pose, velocity and spin (sometimes exactly
    zero) and sometimes its own drag numbers."""
    kind = draw(st.sampled_from(["sphere", "cube", "box", "box", "static"]))
    static = kind == "static"
    body = {"name": f"b{i}", "shape": draw(_shape(draw(st.sampled_from(["sphere", "box"])) if static else kind)),
            "position": draw(_vector(3.0)), "orientation": draw(_unit_quaternion()),
            "mass": draw(_log_uniform(0.1, 100.0))}
    if static:
        return dict(body, static=True)
    if draw(st.integers(0, 4)):
        body["velocity"] = draw(_vector(5.0))
    if draw(st.integers(0, 3)):
        body["angular_velocity"] = draw(_vector(10.0))
    if draw(st.integers(0, 3)) == 0:
        body["drag"] = {"cd": draw(_uniform(0.0, 2.0)), "b": draw(_uniform(0.0, 3.0))}
        if draw(st.booleans()):
            body["drag"]["area"] = draw(_log_uniform(0.01, 2.0))
    return body


def _size(body):
    shape = body["shape"]
    return shape["radius"] if shape["type"] == "sphere" else max(shape["half_extents"])


def _world_point(body, point):
    return np.asarray(body["position"]) + ref.rotate(np.array([body["orientation"]]), np.array([point]))[0]


@st.composite
def _spring(draw, bodies):
    """A spring between two bodies or a body and the world, hooked at the centre
    or off it, stretched or compressed by at least 20 % at the start."""
    n = len(bodies)
    a = draw(st.integers(0, n - 1))
    b = draw(st.integers(-1, n - 2))
    b += b >= a                       # any other body, or the world (-1)
    ends = []
    for j in (a, b):
        if j < 0:
            ends.append(("world", draw(_vector(3.0))))
        elif draw(st.booleans()):
            ends.append((f"b{j}", [0.0, 0.0, 0.0]))
        else:
            ends.append((f"b{j}", (np.array(draw(_vector(1.0))) * _size(bodies[j])).tolist()))
    points = [np.asarray(p) if j < 0 else _world_point(bodies[j], p) for j, (_, p) in zip((a, b), ends)]
    length = float(np.linalg.norm(points[1] - points[0]))
    factor = draw(st.one_of(_uniform(0.0, 0.8), _uniform(1.25, 2.0)))
    return {"a": ends[0][0], "b": ends[1][0], "point_a": ends[0][1], "point_b": ends[1][1],
            "stiffness": draw(_uniform(0.0, 200.0)), "rest_length": length * factor,
            "damping": draw(st.sampled_from([0.0, 0.0, 0.5, 3.0]))}


@st.composite
def _effects(draw, gravity):
    effects = {}
    if draw(st.booleans()):
        effects["drag"] = {"model": draw(st.sampled_from(["linear", "quadratic", "reynolds"])),
                           "fluid_density": draw(_uniform(0.0, 10.0)),
                           "viscosity": draw(_log_uniform(1e-5, 1.0)), "b": draw(_uniform(0.0, 3.0)),
                           "reynolds_threshold": draw(_log_uniform(0.1, 1e4))}
    if draw(st.integers(0, 2)) == 0:
        effects["gravitation"] = {"G": draw(_log_uniform(0.01, 10.0)), "softening": draw(_log_uniform(1e-3, 0.5))}
    if gravity is not None and draw(st.booleans()):
        effects["buoyancy"] = {"fluid_density": draw(_uniform(100.0, 2000.0)),
                               "surface_z": draw(_uniform(-2.0, 2.0)),
                               "linear_damping": draw(st.sampled_from([0.0, 2.0])),
                               "angular_damping": draw(st.sampled_from([0.0, 0.5])),
                               "cells": draw(st.integers(1, 6))}
    return effects


@st.composite
def _gravity(draw):
    g = draw(st.one_of(st.none(), st.just("earth"), _vector(10.0)))
    return None if isinstance(g, list) and not any(g) else g


@st.composite
def _commands(draw, bodies):
    """Held forces (at the centre or at a point on the body) and torques, and sleepers."""
    dynamic = [i for i, b in enumerate(bodies) if not b.get("static")]
    commands = []
    for i in dynamic:
        if draw(st.integers(0, 2)) == 0:
            point = np.asarray(bodies[i]["position"]) + np.array(draw(_vector(1.0))) * _size(bodies[i])
            commands.append(("force", f"b{i}", draw(_vector(20.0)), draw(st.sampled_from([None, point.tolist()]))))
        if draw(st.integers(0, 3)) == 0:
            commands.append(("torque", f"b{i}", draw(_vector(5.0)), None))
    return commands, [i for i in dynamic if draw(st.integers(0, 5)) == 0]


@st.composite
def scenes(draw):
    """(scene dict, held forces and torques, sleeping bodies)."""
    n = draw(st.integers(1, 6))
    bodies = [draw(_body(i)) for i in range(n)]
    gravity = draw(_gravity())
    sc = {"dt": draw(st.sampled_from([1 / 240, 1 / 60, 1e-3])), "integrator": draw(st.sampled_from(INTEGRATORS)),
          "bodies": bodies, "effects": draw(_effects(gravity)),
          "springs": [draw(_spring(bodies)) for _ in range(draw(st.integers(0, 3)))]}
    if gravity is not None:
        sc["gravity"] = gravity
    commands, sleepers = draw(_commands(bodies))
    return sc, commands, sleepers


def _prepare(world, commands, sleepers):
    for kind, name, value, point in commands:
        if kind == "force":
            world.apply_force(name, value, point=point)
        else:
            world.apply_torque(name, value)
    for i in sleepers:
        world.state.awake[i] = False
    world.refresh_awake()
    return world


def _lever(sc):
    """The largest lever arm in the scene (body sizes, spring attachments), m."""
    arms = [_size(b) for b in sc["bodies"]]
    arms += [float(np.linalg.norm(s[k])) for s in sc.get("springs", []) for k in ("point_a", "point_b")
             if s[k[-1]] != "world"]
    return max(arms)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@SETTINGS
@given(scenes(), st.integers(0, 2 ** 32 - 1))
def test_force_effects_add_into_what_the_accumulators_hold(case, seed):
    """Each effect's apply adds into F and τ (it does not overwrite them), as the
    reference's does: started from random accumulators, the sums agree."""
    sc, _, _ = case
    world = load_scene(sc)
    new, old = build_force_effects(world.model), ref.build_force_effects(world.model)
    assert [name for name, _ in new] == [name for name, _ in old]
    rng = np.random.default_rng(seed)
    s = world.state
    kin = Kinematics(s.pos, s.quat, s.vel, s.omega)
    for (name, apply), (_, apply_ref) in zip(new, old):
        F0, T0 = rng.normal(size=s.pos.shape), rng.normal(size=s.pos.shape)
        F, T, F_ref, T_ref = F0.copy(), T0.copy(), F0.copy(), T0.copy()
        apply(kin, F, T)
        apply_ref(kin, F_ref, T_ref)
        scale = max(_norm(F_ref - F0), 1.0)
        _check(f"effect {name}: force", F, F_ref, scale)
        _check(f"effect {name}: torque", T, T_ref, max(_norm(T_ref - T0), scale * _lever(sc), 1.0))


# ---- free rotation on arbitrary inertias ------------------------------------------

@st.composite
def rotation_rows(draw):
    """Orientations, momenta and principal moments: isotropic rows, mild ones and
    strongly asymmetric ones (ratios up to 1e4), some bodies not spinning."""
    n = draw(st.integers(1, 12))
    rng = np.random.default_rng(draw(st.integers(0, 2 ** 32 - 1)))
    q = ref.normalize(rng.normal(size=(n, 4)))
    L = rng.normal(size=(n, 3)) * draw(_log_uniform(1e-3, 1e3))
    kind = rng.integers(0, 3, size=n)
    inertia = np.exp(rng.uniform(-1.0, 1.0, size=(n, 3)))
    inertia[kind == 0] = inertia[kind == 0, :1]                                # isotropic
    inertia[kind == 2] *= np.exp(rng.uniform(-4.6, 4.6, size=(np.sum(kind == 2), 3)))   # up to 1e4 : 1
    L[rng.random(n) < 0.2] = 0.0
    h = draw(st.sampled_from([1 / 240, 1 / 60, 0.05]))
    return q, L, inertia, ref.isotropic_rows(inertia), h


@SETTINGS
@given(rotation_rows(), st.booleans())
def test_free_rotation_matches_the_numpy_splitting(rows, split_all):
    """advance (exact map for isotropic rows, the principal-axis splitting for the
    others), L = I_w ω, ω = I_w⁻¹ L and turn, row by row, agree to 1e-12 with the
    numpy versions; split_all sends every row through the splitting."""
    q, L, inertia, iso, h = rows
    if split_all:
        iso = np.zeros(len(q), dtype=bool)
    inv = 1.0 / inertia
    got_q, got_w = free_rotation.advance(q, L, inv, h, free_rotation.RowSplit(iso))
    want_q, want_w = ref.advance(q, L, inv, h, ref.RowSplit(iso))
    _check("free rotation: q", got_q, want_q, 1.0)
    _check("free rotation: omega", got_w, want_w, max(_norm(want_w), 1e-300))
    omega = ref.world_velocity(q, inv, L, ref.RowSplit(iso))
    _check("free rotation: L = I_w w", free_rotation.world_momentum(q, inertia, omega, iso),
           ref.world_momentum(q, inertia, omega, iso), max(_norm(L), 1e-300))
    _check("free rotation: w = I_w^-1 L", free_rotation.world_velocity(q, inv, L, iso), omega,
           max(_norm(omega), 1e-300))
    _check("free rotation: turn", free_rotation.turn(q, omega, h), ref.turn(q, omega, h), 1.0)
