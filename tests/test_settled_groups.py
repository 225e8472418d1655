"""The shock sweep leaves out groups of bodies the sweeps settled
(shock_propagation.leave_out_settled): a movable body is kept exactly when
it is connected, through movable bodies, to a manifold whose last sweep
changed an impulse by the bound or more. Checked against a union–find over
random contact graphs (Hypothesis), and on a scene: a lone resting cube
beside a stack with a 1000:1 mass ratio, where the stack keeps its sweep and
the cube's velocities are not touched, and where the friction computed
again for the contacts of the bodies the sweep may have moved
(swept_bodies) equals that computed again for every contact.
"""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics_core import load_scene
from physics_core.collision import shock_propagation as SP
from physics_core.collision.contact_data import (ITERATIONS, RESTING_BLOCK, SHOCK_ON,
                                                 VELOCITY_TOLERANCE)
from physics_core.collision.contact_layout import BODY_A, BODY_B, ICOL, INV_MASS_A, INV_MASS_B, NCOL
from physics_core.collision.contact_stages import SETTLE
from physics_core.collision.manifold_friction import FIRST, MICOL
from physics_core.collision.scratch import empty_store
from physics_core.collision.sequential_impulses import (friction_and_slip, friction_of,
                                                        least_mass, solve_velocities)
from substep_rows import rows_after_sweeps, rows_before_solve

DT = 1 / 240


def _groups(n, I, movable):
    """Union–find root of every body over the contacts between movable bodies."""
    root = list(range(n))

    def find(i):
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i
    for a, b in I[:, :2]:
        if movable[a] and movable[b]:
            root[find(a)] = find(b)
    return [find(i) for i in range(n)]


def _reference(I, layer, changes, bound):
    n = len(layer)
    movable = (layer != 0) & (layer != SP.UNREACHED)
    group = _groups(n, I, movable)
    seeds = {group[x] for k in range(len(I)) if not changes[k] < bound
             for x in I[k, :2] if movable[x]}
    keep = np.array([bool(movable[i]) and group[i] in seeds for i in range(n)])
    want = layer.copy()
    want[(layer != 0) & ~keep] = SP.UNREACHED
    return want, int(keep.sum())


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 40), contacts=st.integers(0, 80),
       settled=st.floats(0.0, 1.0), immovable=st.floats(0.0, 0.5))
def test_a_body_is_kept_only_with_an_unsettled_manifold_in_its_group(seed, n, contacts, settled,
                                                                      immovable):
    rng = np.random.default_rng(seed)
    I = np.zeros((contacts, ICOL), np.int64)
    I[:, BODY_A] = rng.integers(0, n, contacts)
    I[:, BODY_B] = (I[:, BODY_A] + rng.integers(1, n, contacts)) % n
    fixed = rng.random(n) < immovable
    R = np.zeros((contacts, NCOL))
    R[:, INV_MASS_A] = np.where(fixed[I[:, BODY_A]], 0.0, 1.0)
    R[:, INV_MASS_B] = np.where(fixed[I[:, BODY_B]], 0.0, 1.0)
    MI = np.zeros((contacts, MICOL), np.int64)
    MI[:, FIRST] = np.arange(contacts)
    changes = np.where(rng.random(contacts) < settled, 0.5, 2.0)
    changes[rng.random(contacts) < 0.05] = np.nan          # a NaN change is never settled
    store = empty_store()
    layer, graph = SP.support_layers(R, I, MI, n, store)
    before = layer.copy()
    kept = SP.leave_out_settled(I, MI, layer, graph, (changes, 1.0), store)
    want, count = _reference(I, before, changes, 1.0)
    assert np.array_equal(layer, want)
    assert kept == count


def _cube(name, x, z, mass=1.0):
    return {"name": name, "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.1]},
            "mass": mass, "position": [x, 0.0, z]}


def _swept(extra, steps):
    """A lone cube, a 1 kg cube under a 1,000 kg one and `extra` bodies after
    `steps` steps, then one substep's rows solved by the sweeps as
    solve_stage runs them: (world, R, I, M, MI, vel, omega, quat, store,
    each manifold's last change, the skip's bound)."""
    w = load_scene({"dt": DT, "gravity": "earth", "effects": {"contacts": {"sleep": False}},
                    "bodies": [{"name": "floor", "shape": {"type": "plane"}, "static": True},
                               _cube("lone", 1.0, 0.1), _cube("light", 0.0, 0.1),
                               _cube("heavy", 0.0, 0.3, mass=1000.0)] + extra})
    w.step(steps)
    return (w,) + rows_after_sweeps(w, DT)


def test_a_settled_cube_is_left_out_beside_an_unsettled_stack():
    w, R, I, M, MI, vel, omega, quat, store, changes, bound = _swept([], 240)
    fp, ip = w.contact_system.fp, w.contact_system.ip
    lone = list(w.model.names).index("lone")
    of_lone = (I[MI[:, FIRST], BODY_A] == lone) | (I[MI[:, FIRST], BODY_B] == lone)
    assert (changes[of_lone] < bound).all(), "the lone cube's sweeps did not settle"
    assert not (changes[~of_lone] < bound).all(), "the 1000:1 stack settled in its sweeps"
    v, o = vel.copy(), omega.copy()
    visited, _ = SP.shock_sweep(R, I, M, MI, v, o, len(v), ip[SHOCK_ON],
                             SETTLE * fp[VELOCITY_TOLERANCE], (w._inv_mass, w.inv_inertia, quat),
                             ip[RESTING_BLOCK] != 0, (changes, bound), store)
    assert visited == int((~of_lone).sum())           # the stack's two manifolds
    assert np.array_equal(v[lone], vel[lone]) and np.array_equal(o[lone], omega[lone])


def test_friction_after_the_sweep_is_the_same_computed_for_the_swept_bodies_alone():
    w, R, I, M, MI, vel, omega, quat, store, changes, bound = _swept([_cube("side", 0.21, 0.1)],
                                                                     120)
    fp, ip = w.contact_system.fp, w.contact_system.ip
    friction, slip = np.zeros((len(R), 3)), np.zeros(len(R))
    friction_and_slip(R, I, vel, omega, friction, slip)
    v0, o0 = vel.copy(), omega.copy()
    visited, layer = SP.shock_sweep(R, I, M, MI, vel, omega, len(vel), ip[SHOCK_ON],
                                    SETTLE * fp[VELOCITY_TOLERANCE],
                                    (w._inv_mass, w.inv_inertia, quat), ip[RESTING_BLOCK] != 0,
                                    (changes, bound), store)
    layer = np.array(layer)
    swept = np.array(SP.swept_bodies(layer, store))
    assert visited > 0 and swept.any() and not swept.all()
    moved = (np.abs(vel - v0).max(axis=1) > 0) | (np.abs(omega - o0).max(axis=1) > 0)
    assert not (moved & ~swept).any(), "a body outside the swept layers changed velocity"
    every_f, every_s = friction.copy(), slip.copy()
    friction_and_slip(R, I, vel, omega, every_f, every_s)
    friction_of(R, I, friction, swept)
    assert np.array_equal(friction, every_f)


@pytest.mark.parametrize("change, before, left, goes_on", [
    (1e-5, 1e-3, 1, True),         # rate 0.01: 1e-7 after one more sweep, under 1e-6
    (1e-5, 1e-3, 0, False),        # no sweep left
    (1e-5, 2e-5, 3, False),        # rate 0.5: 1.25e-6 after three, not under
    (1e-5, 2e-5, 4, True),         # 6.25e-7 after four
    (5e-7, 1e-3, 4, False),        # under the bound already
    (1e-5, 1e-5, 7, False),        # not shrinking
    (np.nan, 1e-3, 7, False),      # NaN: the caller's stop test fails first
])
def test_sweeps_go_on_only_when_their_rate_reaches_the_settle_bound_in_the_sweeps_left(
        change, before, left, goes_on):
    """sequential_impulses._settling against its closed form: the change
    times (change / before) ** left under the bound (1e-6 here)."""
    from physics_core.collision.sequential_impulses import _settling
    assert _settling(change, before, 1e-6, left) is goes_on


def _pyramid_of_three():
    return load_scene({"dt": DT, "gravity": "earth", "effects": {"contacts": {"sleep": False}},
                       "bodies": [{"name": "floor", "shape": {"type": "plane"}, "static": True},
                                  _cube("left", -0.101, 0.1), _cube("right", 0.101, 0.1),
                                  _cube("top", 0.0, 0.301)]})


def test_a_resting_pyramids_sweeps_go_on_to_where_the_shock_sweep_leaves_it_out():
    """Three cubes at rest (two on the floor, one across them): stopped at the
    velocity tolerance the sweeps leave some manifold above the shock
    sweep's bound, so the sweep runs on the whole pyramid every substep;
    converging fast, they go on under it (solve_stage's stops) and the
    pyramid is left out, within the `iterations` the scene allows."""
    w = _pyramid_of_three()
    w.step(240)
    cs = w.contact_system
    ends = {}
    for stops in ("tolerance", "settle"):
        R, I, M, MI, vel, omega, quat, store = rows_before_solve(w, DT)
        limit = cs.fp[VELOCITY_TOLERANCE] * least_mass(R)
        changes = np.empty(len(MI))
        settle = limit if stops == "tolerance" else SETTLE * limit
        sweeps, _ = solve_velocities(R, I, M, MI, vel, omega, cs.ip[ITERATIONS],
                                     (limit, settle, SP.STALL), changes)
        ends[stops] = (sweeps, changes.max(), SETTLE * limit)
    sweeps, change, bound = ends["tolerance"]
    assert change >= bound
    sweeps_settled, change_settled, _ = ends["settle"]
    assert change_settled < bound and sweeps < sweeps_settled <= cs.ip[ITERATIONS]
