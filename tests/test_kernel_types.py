"""Every scene steps with the kernels `make install` compiled: the arrays the
step passes have the same Numba types whatever the scene declares, so no
scene's first step compiles a second set of kernels."""
from numba import typeof

from physics_core import load_scene
from physics_core.collision.contact_data import contact_model
from physics_core.step_loop import no_contacts
from physics_scenes import scene, sphere


def test_scene_without_contacts_gets_the_contact_model_type_of_one_with_contacts():
    """Regression: without the contacts effect the step got a ContactModel of
    writable arrays where a real one has read-only ones: a Numba type of its
    own, so the first step of every such scene compiled all contact stages
    again (over 20 s on a loaded machine, where the node tests' first
    ~/step timed out)."""
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True}
    world = load_scene(scene(ground, sphere("ball", position=(0, 0, 0.5)), gravity="earth",
                             effects={"contacts": {}}))
    assert typeof(no_contacts()[0][0]) == typeof(contact_model(world.model))

