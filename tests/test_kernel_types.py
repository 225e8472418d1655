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


_COMPILES_AT_START = """
from numba.core import event

compiled = []


class Compiles(event.Listener):
    def on_start(self, ev):
        compiled.append(str(ev.data["dispatcher"].py_func.__qualname__))

    def on_end(self, ev):
        pass


event.register("numba:compile", Compiles())
import physics_core
world = physics_core.load_scene(physics_core.default_scene_path())
world.step(1)
print(repr(compiled))
"""


def test_typed_lists_made_in_python_compiled_their_methods_at_every_import():
    """Regression: the warm cache's typed lists were made by Python calls
    (typed.List.empty_list, append), whose compiled methods numba does not
    cache: every `import physics_core` compiled them again, about 1 s of a
    2.1–2.7 s import. Once a process has cached what the default scene
    uses (the first run below: nothing to do after `make install`, the
    whole step after an edit of the engine), importing the engine and
    stepping that scene once compiles nothing (numba's "numba:compile"
    event fires only on a cache miss)."""
    import ast
    import subprocess
    import sys

    def compiled(timeout):
        out = subprocess.run([sys.executable, "-c", _COMPILES_AT_START], capture_output=True,
                             text=True, timeout=timeout, check=True).stdout
        return ast.literal_eval(out.strip().splitlines()[-1])

    compiled(timeout=3600)
    assert compiled(timeout=300) == []
