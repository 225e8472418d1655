"""Shortcuts the step takes must give what the general path gives.

- free rotation: isotropic bodies skip the principal-axis splitting and the
  frame changes of L = I_w ω (I_w = I 1 for them); bodies that do not spin
  keep their orientation untouched;
- broad phase: the pair list kept between steps (a Verlet list) gives the
  same pairs, in the same order, as detecting from scratch every step;
- contact rows: what depends only on the contact set (pair gathers, friction
  coefficients, flat indices, the tangent frame of unchanged normals) is
  reused from the last substep with the same result as building it afresh.
"""
import numpy as np
import pytest

from physics_core import free_rotation, load_scene
from physics_core import quaternion as qt
from physics_scenes import box, scene, sphere


def _random_rotation_rows(rng, n):
    q = qt.normalize(rng.normal(size=(n, 4)))
    L = rng.normal(size=(n, 3))
    inertia = rng.uniform(0.5, 2.0, size=(n, 3))
    iso = rng.random(n) < 0.5
    inertia[iso] = inertia[iso, :1]
    still = rng.random(n) < 0.2
    L[still] = 0.0
    return q, L, inertia, iso


def _reference_advance(q, L, inv_inertia, h, iso):
    """The splitting on every row, then the exact map on the isotropic ones."""
    out, omega = free_rotation._split(q, L, inv_inertia, h)
    omega_iso = L * inv_inertia[:, :1]
    out = np.where(iso[:, None], qt.integrate(q, omega_iso, h), out)
    omega = np.where(iso[:, None], omega_iso, omega)
    return out, omega


@pytest.mark.parametrize("seed", range(5))
def test_isotropic_rows_take_the_exact_map_and_the_rest_the_splitting(seed):
    rng = np.random.default_rng(seed)
    q, L, inertia, iso = _random_rotation_rows(rng, 40)
    inv = 1.0 / inertia
    h = 0.01
    for mask in (iso, np.ones(40, bool), np.zeros(40, bool)):
        ref_q, ref_w = _reference_advance(q, L, inv, h, mask)
        got_q, got_w = free_rotation.advance(q, L, inv, h, free_rotation.RowSplit(mask))
        np.testing.assert_allclose(got_q, ref_q, rtol=0, atol=1e-15)
        np.testing.assert_allclose(got_w, ref_w, rtol=0, atol=1e-14)


def test_a_body_that_does_not_spin_keeps_its_orientation_bit_for_bit():
    rng = np.random.default_rng(3)
    q = qt.normalize(rng.normal(size=(6, 4)))
    omega = rng.normal(size=(6, 3))
    omega[[1, 4]] = 0.0
    out = free_rotation.turn(q, omega, 0.01)
    assert np.array_equal(out[[1, 4]], q[[1, 4]])
    np.testing.assert_allclose(out[[0, 2, 3, 5]], qt.integrate(q, omega, 0.01)[[0, 2, 3, 5]], atol=1e-15)


@pytest.mark.parametrize("seed", range(3))
def test_world_momentum_and_velocity_match_the_frame_change(seed):
    rng = np.random.default_rng(seed)
    q, w, inertia, iso = _random_rotation_rows(rng, 30)
    rows = free_rotation.RowSplit(iso)
    L_ref = qt.rotate(q, inertia * qt.rotate_inverse(q, w))
    L = free_rotation.world_momentum(q, inertia, w, rows)
    np.testing.assert_allclose(L, L_ref, rtol=0, atol=1e-14)
    w_back = free_rotation.world_velocity(q, 1.0 / inertia, L, rows)
    np.testing.assert_allclose(w_back, w, rtol=0, atol=1e-13)


@pytest.mark.parametrize("integrator", ["explicit_euler", "semi_implicit_euler", "velocity_verlet", "rk4"])
def test_a_mixed_scene_steps_like_the_general_path(integrator):
    """Spinning spheres, cubes and a tumbling box under a held torque: the
    World (with its isotropic shortcuts) against the same World told that no
    body is isotropic (every row through the general formulas)."""
    bodies = [sphere("s", position=(0, 0, 0), angular_velocity=[1.0, -2.0, 0.5]),
              box("cube", half_extents=(0.2, 0.2, 0.2), position=(1, 0, 0),
                  angular_velocity=[0.3, 0.0, 2.0]),
              box("slab", half_extents=(0.4, 0.25, 0.1), position=(2, 0, 0),
                  angular_velocity=[0.1, 3.0, 0.2]),
              sphere("rest", position=(3, 0, 0))]
    fast = load_scene(scene(*bodies, integrator=integrator))
    slow = load_scene(scene(*bodies, integrator=integrator))
    slow.rotation_rows = free_rotation.RowSplit(np.zeros(slow.model.n, bool))
    slow.isotropic = np.zeros(slow.model.n, bool)
    for w in (fast, slow):
        w.apply_torque("cube", [0.0, 0.2, 0.0])
        w.step(240)
    np.testing.assert_allclose(fast.state.omega, slow.state.omega, rtol=0, atol=1e-9)
    if integrator in ("explicit_euler", "rk4"):
        # both paths use the same orientation update; only L = I_w ω differs in round-off
        np.testing.assert_allclose(fast.state.quat, slow.state.quat, rtol=0, atol=1e-9)
    else:
        # the general path splits the isotropic rows too: same rotation, to second order
        np.testing.assert_allclose(fast.state.quat[[2]], slow.state.quat[[2]], rtol=0, atol=1e-9)
    assert np.array_equal(fast.state.quat[3], [1.0, 0.0, 0.0, 0.0])


def _pile(sleep):
    """Spheres and boxes dropped onto a floor and onto each other."""
    rng = np.random.default_rng(7)
    bodies = [{"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}}]
    for i in range(24):
        x, y = (i % 4) * 0.3 + rng.uniform(-0.05, 0.05), (i // 4 % 3) * 0.3
        z = 0.15 + 0.35 * (i // 12) + rng.uniform(0.0, 0.05)
        if i % 3:
            bodies.append(sphere(f"s{i}", radius=0.1, position=(x, y, z)))
        else:
            bodies.append(box(f"b{i}", half_extents=(0.12, 0.08, 0.1), position=(x, y, z),
                              angular_velocity=[0.5, -0.3, 1.0]))
    return scene(*bodies, dt=1.0 / 240.0, gravity="earth", effects={"contacts": {"sleep": sleep}},
                 friction=[{"a": "default", "b": "default", "static": 0.6, "kinetic": 0.5}])


@pytest.mark.parametrize("sleep", [False, True])
def test_a_pile_steps_bit_for_bit_with_and_without_the_kept_pair_list(sleep):
    kept = load_scene(_pile(sleep))
    fresh = load_scene(_pile(sleep))
    fresh.step(1)
    kept.step(1)
    fresh.state.scratch["contacts"].pairs = None      # broad phase from scratch every step
    for _ in range(6):
        kept.step(50)
        fresh.step(50)
        for name in ("pos", "quat", "vel", "omega", "awake"):
            assert np.array_equal(getattr(kept.state, name), getattr(fresh.state, name)), name
    assert kept.state.scratch["contacts"].pairs.builds < 200     # the list was kept in between


class _NoReuse:
    """A row cache that never matches: every substep builds its rows afresh."""

    def __new__(cls):
        from physics_core.collision.contact_rows import RowCache

        class Never(RowCache):
            def pairs_match(self, key, masses):
                return False
        return Never()


def _resting_spheres(sleep):
    rng = np.random.default_rng(3)
    bodies = [{"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}}]
    for i in range(16):
        bodies.append(sphere(f"s{i}", radius=0.1, position=((i % 4) * 0.25, (i // 4) * 0.25,
                                                           0.1 + 0.02 * rng.random())))
    return scene(*bodies, dt=0.001, gravity="earth", effects={"contacts": {"sleep": sleep}},
                 friction=[{"a": "default", "b": "default", "static": 0.6, "kinetic": 0.5}])


@pytest.mark.parametrize("make", [_pile, _resting_spheres])
@pytest.mark.parametrize("sleep", [False, True])
def test_contact_rows_reused_from_the_last_substep_step_bit_for_bit(make, sleep):
    kept = load_scene(make(sleep))
    fresh = load_scene(make(sleep))
    fresh.step(1)
    kept.step(1)
    fresh.state.scratch["contacts"].row_cache = _NoReuse()
    for _ in range(6):
        kept.step(50)
        fresh.step(50)
        for name in ("pos", "quat", "vel", "omega", "awake"):
            assert np.array_equal(getattr(kept.state, name), getattr(fresh.state, name)), name
        for name in ("point", "normal", "impulse", "friction_impulse", "normal_speed", "event"):
            assert np.array_equal(getattr(kept.contacts, name), getattr(fresh.contacts, name)), name
    assert kept.state.scratch["contacts"].row_cache.key is not None


def test_spheres_on_a_plane_give_the_kernels_contacts_from_the_kept_pair_list():
    from physics_core.collision.narrowphase import collide
    from physics_core.collision.pair_cache import PairCache

    w = load_scene(_resting_spheres(False))
    cache = PairCache(w.model)
    margin = 0.001
    for _ in range(40):
        w.step(5)
        kept = collide(w.model, w.state.pos, w.state.quat, margin, cache)
        fresh = collide(w.model, w.state.pos, w.state.quat, margin)
        for name in ("a", "b", "point", "normal", "depth", "key"):
            assert np.array_equal(getattr(kept, name), getattr(fresh, name)), name
    assert cache.plane_sphere and cache.memo is not None
    # a sphere lifted out of reach: the kept list still holds its pair, the
    # kernels' filter drops it
    w.state.pos[1, 2] += 0.05
    kept = collide(w.model, w.state.pos, w.state.quat, margin, cache)
    fresh = collide(w.model, w.state.pos, w.state.quat, margin)
    assert len(kept) == len(fresh) == 15
    for name in ("a", "b", "point", "normal", "depth", "key"):
        assert np.array_equal(getattr(kept, name), getattr(fresh, name)), name


def _restitution_in_full(pipeline, world, h):
    """The restitution stage without its early return (the general path)."""
    from physics_core.collision import restitution, solver

    sc = pipeline.scratch(world)
    rows = sc.rows
    if rows is None:
        return
    approach = -rows.u0[:, 0]
    e = restitution.effective(rows.e, approach, pipeline.p.restitution_threshold,
                              pipeline.p.restitution_ramp)
    active = (e > 0.0) & (rows.lam[:, 0] > 0.0)
    sc.bounce = None
    if np.count_nonzero(active):
        solver.solve_normal_targets(sc.V, rows, e * approach, active, 1, pipeline.summed)
        i = np.flatnonzero(active)
        s0 = approach[i] * h - rows.depth[i]
        tau = np.clip(s0 / np.maximum(approach[i] * h, 1e-300), 0.0, 1.0)
        sc.bounce = (np.concatenate([rows.a[i], rows.b[i]]), np.concatenate([tau, tau]))


@pytest.mark.parametrize("ramp", [0.0, 0.3])
def test_restitution_skipped_when_nothing_approaches_fast_steps_like_the_full_stage(ramp):
    import functools

    def bouncing():
        bodies = [{"name": "ground", "shape": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0}}]
        for i in range(6):
            bodies.append(sphere(f"s{i}", radius=0.1, position=(0.3 * i, 0.0, 0.15 + 0.1 * i)))
            bodies[-1]["restitution"] = 0.6
        return scene(*bodies, dt=0.001, gravity="earth",
                     effects={"contacts": {"sleep": False, "restitution_ramp": ramp}},
                     friction=[{"a": "default", "b": "default", "static": 0.6, "kinetic": 0.5}])

    fast, full = load_scene(bouncing()), load_scene(bouncing())
    i = [n for n, _ in full._contact_stages].index("restitution")
    pipeline = full._contact_stages[i][1].__self__
    full._contact_stages[i] = ("restitution", functools.partial(_restitution_in_full, pipeline))
    bounced = 0
    for _ in range(600):
        fast.step(1)
        full.step(1)
        bounced += fast.state.scratch["contacts"].bounce is not None
        for name in ("pos", "quat", "vel", "omega"):
            assert np.array_equal(getattr(fast.state, name), getattr(full.state, name)), name
    assert 0 < bounced < 600     # some steps bounced, others took the early return
