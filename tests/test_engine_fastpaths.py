"""Shortcuts the step takes must give what the general path gives.

- free rotation: isotropic bodies skip the principal-axis splitting and the
  frame changes of L = I_w ω (I_w = I 1 for them); bodies that do not spin
  keep their orientation untouched.
"""
import numpy as np
import pytest

from physics_core import free_rotation, load_scene
from physics_core.integration import integration_data
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
    slow._idata = integration_data(slow.model, isotropic=np.zeros(slow.model.n, bool))
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
