"""Whether this engine can simulate contacts yet, and which contact settings it reads.

The contact studies (bouncing heights, time-of-impact bisection, solver
iterations, piles and pyramids) call `available()` first and skip with its
reason instead of failing when the `contacts` effect cannot be built.
"""
import dataclasses
import functools
import warnings

from physics_core import PhysicsError, SceneError, load_scene

PROBE = {"dt": 1.0 / 240.0, "gravity": "earth", "effects": {"contacts": {}},
         "bodies": [{"name": "ground", "shape": {"type": "plane"}, "static": True,
                     "material": "concrete"},
                    {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
                     "material": "rubber", "position": [0.0, 0.0, 0.11]}]}


@functools.lru_cache(maxsize=1)
def available():
    """(True, "") when a scene with contacts loads and steps, else (False, why)."""
    try:
        with warnings.catch_warnings():
            # the probe's own friction pairs are not the point here
            warnings.simplefilter("ignore", UserWarning)
            world = load_scene(PROBE)
        world.step(5)
    except (NotImplementedError, ImportError, AttributeError, PhysicsError, SceneError) as e:
        return False, f"{type(e).__name__}: {e}"
    return True, ""


def settings():
    """Names of the keys `effects.contacts` accepts (contact_params.py)."""
    from physics_core import contact_params
    keys = getattr(contact_params, "CONTACT_KEYS", None)
    if keys is None:
        keys = {f.name for f in dataclasses.fields(contact_params.ContactParams)}
    return set(keys)


def has_setting(*names):
    return set(names) <= settings()


def skipped(study, reason):
    """The Markdown a skipped contact study writes in place of its tables."""
    return (f"# {study}\n\n_Skipped: contacts are not available in this build of the engine "
            f"({reason})._\n")
