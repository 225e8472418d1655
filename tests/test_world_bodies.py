"""Bodies added and removed between steps (INTERFACE.md: world.add_body / remove_body).

A body added between steps is validated like a scene body, becomes the last
body, and from then on moves exactly as if the scene had declared it; a
removed body leaves the others stepping as if it had never been there, and
its contacts end with an `end` event. Neither recompiles a kernel.
"""
import numpy as np
import pytest

from physics_core import END, CommandError, SceneError, load_scene
from physics_scenes import box, scene, sphere, state_hash

pytestmark = pytest.mark.filterwarnings("ignore:.*fallback")
GROUND = {"name": "ground", "shape": {"type": "plane"}, "static": True}
CONTACTS = {"contacts": {}}


def pile_scene(*bodies):
    return scene(GROUND, *bodies, gravity="earth", effects=CONTACTS)


def test_an_added_body_steps_bit_for_bit_like_a_scene_body():
    """Same bodies, same order: adding the last one before the first step is the
    scene that declares it."""
    ball, crate = sphere(position=(0, 0, 0.5)), box("crate", position=(0.2, 0, 1.0))
    grown = load_scene(pile_scene(ball))
    view = grown.add_body(crate)
    declared = load_scene(pile_scene(ball, crate))
    grown.step(200)
    declared.step(200)
    assert view.name == "crate" and view.index == 2
    assert state_hash(grown) == state_hash(declared)


def test_a_removed_body_leaves_the_world_of_the_others():
    a, b, c = (sphere(n, position=(x, 0, 0.3)) for n, x in (("a", 0.0), ("b", 1.0), ("c", 2.0)))
    full = load_scene(pile_scene(a, b, c))
    full.remove_body("b")
    without = load_scene(pile_scene(a, c))
    full.step(150)
    without.step(150)
    assert full.model.names == ("ground", "a", "c")
    assert state_hash(full) == state_hash(without)


def test_a_removed_resting_body_ends_its_contacts():
    world = load_scene(pile_scene(sphere(position=(0, 0, 0.1)), sphere("other", position=(1, 0, 0.1))))
    world.step(30)
    assert len(world.contacts) >= 2
    world.remove_body("ball")
    world.step()
    ended = world.contacts.event == END
    assert ended.sum() == 1, world.contacts
    # the removed body is reported as -1, its partner (the ground) by its index
    assert world.contacts.body_a[ended][0] == 0 and world.contacts.body_b[ended][0] == -1
    assert (world.contacts.event[~ended] != END).all()


def test_a_body_added_while_others_rest_keeps_their_warm_contacts():
    """The resting pile keeps its contact impulses across the change: the ball on
    the floor persists (no begin, no end) and does not jump."""
    world = load_scene(pile_scene(sphere(position=(0, 0, 0.1))))
    world.step(120)
    z = world.body("ball").position[2]
    world.add_body(sphere("late", position=(3, 0, 1.0)))
    world.step()
    assert set(world.contacts.event.tolist()) == {1}       # persist only
    assert abs(world.body("ball").position[2] - z) < 1e-6


@pytest.mark.parametrize("spec, where", [
    ({"name": "x", "shape": {"type": "sphere", "radius": -1.0}, "mass": 1.0}, "shape.radius"),
    ({"name": "x", "shape": {"type": "sphere", "radius": 0.1}}, "mass"),
    ({"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0}, "name"),
    ({"name": "x", "shape": {"type": "box", "half_extents": [1, 1]}, "mass": 1.0}, "shape.half_extents"),
    ({"name": "x", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0, "colour": 1}, "colour"),
    ({"name": "9x", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0}, "name"),
])
def test_a_bad_body_is_refused_naming_the_key(spec, where):
    world = load_scene(pile_scene(sphere()))
    before = state_hash(world)
    with pytest.raises(SceneError, match=f"add_body: {where}"):
        world.add_body(spec)
    assert world.model.n == 2 and state_hash(world) == before


def test_removing_an_unknown_body_is_refused():
    world = load_scene(pile_scene(sphere()))
    with pytest.raises(CommandError, match="unknown body 'nope'"):
        world.remove_body("nope")


def test_reset_returns_to_the_scene_bodies():
    world = load_scene(pile_scene(sphere(position=(0, 0, 0.5))))
    fresh = load_scene(pile_scene(sphere(position=(0, 0, 0.5))))
    world.add_body(sphere("extra", position=(1, 0, 1)))
    world.remove_body("ball")
    world.step(10)
    world.reset()
    assert world.model.names == ("ground", "ball")
    world.step(50)
    fresh.step(50)
    assert state_hash(world) == state_hash(fresh)


def test_reset_after_a_body_was_added_does_not_size_arrays_by_the_old_state():
    """Regression: reset() rebuilt the step for the scene's bodies while the
    state still held the added one ('operands could not be broadcast')."""
    world = load_scene(pile_scene(sphere(position=(0, 0, 0.5))))
    fresh = load_scene(pile_scene(sphere(position=(0, 0, 0.5))))
    world.add_body(sphere("extra", position=(1, 0, 1)))
    world.step(5)
    world.reset()
    assert world.model.names == ("ground", "ball")
    world.step(50)
    fresh.step(50)
    assert state_hash(world) == state_hash(fresh)


def test_arrays_grow_by_doubling_and_no_kernel_recompiles():
    """Adding 200 bodies one at a time reallocates the state's buffers O(log n) times,
    and the compiled contact kernels keep the signatures they had."""
    from physics_core.collision.contact_build import build_rows
    world = load_scene(pile_scene(sphere(position=(0, 0, 0.1))))
    world.step(2)
    signatures = len(build_rows.signatures)
    buffers = set()
    for i in range(200):
        world.add_body(sphere(f"s{i}", position=(0.3 * (i % 20), 0.3 * (i // 20) + 1, 0.1)))
        buffers.add(id(world.state._buffers["pos"]))
        world.step()
    assert world.model.n == 202 and len(world.state.pos) == 202
    assert len(buffers) <= 9            # 4, 8, ..., 256 rows
    assert len(build_rows.signatures) == signatures
    assert np.isfinite(world.state.pos).all()
