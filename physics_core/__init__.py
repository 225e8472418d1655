"""physics_core: a data-oriented rigid-body engine compiled with Numba (no ROS here).

    from physics_core import load_scene
    world = load_scene("scenes/pile.yaml")
    world.step(100)
"""
import os

from .inline_copies import share_inline_copies
from .kernel_cache import use_source_keyed_cache
from .refcounts import inline_reference_counts

use_source_keyed_cache()      # before any kernel is defined (kernel_cache.py)
inline_reference_counts()     # before numba's runtime is compiled (refcounts.py)
share_inline_copies()         # a cold compile in a fraction of the time (inline_copies.py)

from .contact_events import BEGIN, END, PERSIST, ContactEvents
from .errors import CommandError, NonFiniteStateError, PhysicsError, SceneError
from .scene_loader import build_model, load_scene
from .shapes import BOX, PLANE, SPHERE
from .world import World

__version__ = "0.1.0"


def default_scene_path() -> str:
    """The built-in default scene, shipped inside the package."""
    return os.path.join(os.path.dirname(__file__), "data", "default.yaml")


__all__ = ["load_scene", "build_model", "World", "SceneError", "CommandError", "PhysicsError",
           "NonFiniteStateError", "ContactEvents", "BEGIN", "PERSIST", "END",
           "SPHERE", "BOX", "PLANE", "default_scene_path", "__version__"]
