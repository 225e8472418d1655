"""The broad phase's kept pairs (collision/kept_pairs.py): while bodies move,
turn, jump and change, the pairs the step's broad phase gives from what it
kept are exactly the numpy reference broad phase's, and a World whose kept
pairs are dropped before every step steps to the same bits."""
import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from numpy_reference.broadphase import candidate_pairs as numpy_pairs
from physics_core import load_scene
from physics_core.collision.broad_phase import scratch_pairs
from physics_core.collision.geometry import Geometry
from physics_core.collision.grid import COLS, solid_table
from physics_core.collision.kept_pairs import kept_table
from physics_core.collision.scratch import KEPT, new_counts, new_scratch, open_arena
from physics_core.shapes import PLANE
from random_fields import jiggled, mixed_scene


class StepBroadPhase:
    """The step's broad phase with its scratch and kept pairs, called from
    Python one substep at a time."""

    def __init__(self, model):
        self.g = Geometry.from_model(model)
        self.scratch, self.counts = new_scratch(), new_counts()
        self.solid = np.flatnonzero(self.g.kind != PLANE)

    def holds(self, pos, quat, margin):
        """Whether the kept pairs cover these poses (no grid run needed)."""
        g = self.g
        cols = solid_table(g.kind, g.dims, g.reach, pos, quat, margin, self.solid,
                           np.empty((len(self.solid), COLS)))
        return bool(kept_table(self.scratch[1], self.counts, cols, margin)[1])

    def pairs(self, pos, quat, margin):
        g, store = self.g, open_arena(self.scratch, self.counts)
        return np.array(scratch_pairs(g.kind, g.dims, g.is_static, g.reach, pos, quat, margin,
                                      store))


def assert_numpy_pairs(model, got, pos, quat, margin):
    a, b = numpy_pairs(model, pos, quat, margin)
    assert np.array_equal(got[:, 0], a) and np.array_equal(got[:, 1], b)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), n=st.integers(2, 60), spread=st.floats(0.3, 5.0),
       margin=st.sampled_from([0.0, 0.01, 0.2]), n_planes=st.integers(0, 2),
       big=st.sampled_from([0.0, 0.1]), shift=st.sampled_from([1e-4, 3e-3, 0.05]))
def test_kept_pairs_are_the_numpy_pairs_while_bodies_move(seed, n, spread, margin, n_planes, big,
                                                          shift):
    """Twenty substeps of random moves and turns (static bodies stay), one
    body thrown across the scene every fifth: every substep's pairs, in
    order, are the reference's."""
    rng = np.random.default_rng(seed)
    model, pos, quat = mixed_scene(rng, n + n_planes, spread, n_planes, big)
    broad = StepBroadPhase(model)
    for sub in range(20):
        assert_numpy_pairs(model, broad.pairs(pos, quat, margin), pos, quat, margin)
        pos, quat = jiggled(pos, quat, model.is_static, rng, shift, 10 * shift)
        if sub % 5 == 4:
            pos[rng.integers(len(pos))] = rng.uniform(-spread, spread, 3)


def test_a_scene_at_rest_keeps_its_pairs_and_a_body_that_leaves_its_box_runs_the_grid():
    """Bodies moving by far less than the skin keep their pairs substep after
    substep, from the second grid run on (the first finds the kept buffer
    empty and asks for its room); one thrown out of its fat box does not
    (the grid runs again), nor does a change of margin; the pairs are the
    reference's throughout."""
    rng = np.random.default_rng(7)
    model, pos, quat = mixed_scene(rng, 61, 1.5, 1, 0.0)
    broad = StepBroadPhase(model)
    assert not broad.holds(pos, quat, 0.01), "nothing kept before the first substep"
    assert_numpy_pairs(model, broad.pairs(pos, quat, 0.01), pos, quat, 0.01)
    assert not broad.holds(pos, quat, 0.01), "the first grid run asks for the room to keep"
    for _ in range(10):
        assert_numpy_pairs(model, broad.pairs(pos, quat, 0.01), pos, quat, 0.01)
        pos, quat = jiggled(pos, quat, model.is_static, rng, 1e-6, 1e-6)
        assert broad.holds(pos, quat, 0.01)
    mover = int(np.flatnonzero(~model.is_static)[0])
    pos[mover] += 0.5
    assert not broad.holds(pos, quat, 0.01)
    assert_numpy_pairs(model, broad.pairs(pos, quat, 0.01), pos, quat, 0.01)
    assert broad.holds(pos, quat, 0.01)
    assert not broad.holds(pos, quat, 0.2)
    assert_numpy_pairs(model, broad.pairs(pos, quat, 0.2), pos, quat, 0.2)


def _pile(n=40):
    rng = np.random.default_rng(3)
    bodies = [{"name": "ground", "shape": {"type": "plane"}, "static": True}]
    for i in range(n):
        shape = ({"type": "sphere", "radius": 0.1} if i % 3 else
                 {"type": "box", "half_extents": [0.08, 0.1, 0.06]})
        x, y = (i % 4) * 0.21 + rng.uniform(-0.01, 0.01), ((i // 4) % 4) * 0.21
        bodies.append({"name": f"b{i}", "shape": shape, "mass": 1.0,
                       "position": [x, y, 0.15 + (i // 16) * 0.22]})
    scene = {"dt": 1 / 240, "gravity": [0.0, 0.0, -9.81], "bodies": bodies,
             "effects": {"contacts": {"sleep": False}}}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return load_scene(scene)


def _run(world, steps, drop):
    for _ in range(steps):
        if drop:
            world.contact_system.cap[KEPT] = -1
        world.step(1)


def test_dropping_the_kept_pairs_before_every_step_changes_no_bit():
    """A falling pile of spheres and boxes, with a body removed and one added
    on the way: kept pairs or a fresh grid at every step, the same bits.
    (Removing or adding a body drops what was kept: the pairs name bodies
    by their old numbers.)"""
    worlds = [_pile(), _pile()]
    for drop, world in enumerate(worlds):
        world.substeps = 1
        _run(world, 60, drop)
        world.remove_body("b5")
        assert world.contact_system.cap[KEPT] == -1
        _run(world, 30, drop)
        world.add_body({"name": "late", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
                        "position": [0.3, 0.3, 1.0]})
        assert world.contact_system.cap[KEPT] == -1
        _run(world, 60, drop)
    kept, fresh = worlds
    assert kept.contact_system.cap[KEPT] > 0, "the pile at rest keeps its pairs"
    for field in ("pos", "quat", "vel", "omega"):
        assert np.array_equal(getattr(kept.state, field), getattr(fresh.state, field)), field
