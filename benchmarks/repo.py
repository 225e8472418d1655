"""Where this checkout is, for the studies that start child processes from it."""
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def on_path(env):
    """A copy of `env` whose PYTHONPATH starts with this checkout, so that a child
    process imports physics_core and benchmarks from it."""
    return dict(env, PYTHONPATH=os.pathsep.join([REPO, env.get("PYTHONPATH", "")]).rstrip(os.pathsep))
