"""Compile every kernel once and keep it in Numba's on-disk cache.

    python -m physics_core.warm_up

`make install` runs this, so the first `make run` and every test process
load compiled code (about 0.2 s) instead of compiling it (tens of seconds).
It steps small scenes that reach every kernel: each integrator and force
effect, every shape pair, contacts with ccd, restitution, position
correction, events and sleep. Numba recompiles a kernel by itself when its
source file changes, so a stale cache is never used.
"""
import sys
import warnings
from time import perf_counter

from . import default_scene_path, load_scene
from .scene_loader import INTEGRATORS


def _contact_scene(integrator):
    ground = {"name": "ground", "shape": {"type": "plane"}, "static": True}
    bodies = [ground,
              {"name": "ball", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
               "position": [0.0, 0.0, 0.3], "velocity": [0.0, 0.0, -3.0]},
              {"name": "ball2", "shape": {"type": "sphere", "radius": 0.1}, "mass": 1.0,
               "position": [0.05, 0.0, 0.52]},
              {"name": "crate", "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.1]},
               "mass": 1.0, "position": [0.5, 0.0, 0.12], "angular_velocity": [0.0, 1.0, 0.0]},
              {"name": "crate2", "shape": {"type": "box", "half_extents": [0.1, 0.1, 0.1]},
               "mass": 1.0, "position": [0.55, 0.02, 0.33]},
              {"name": "bullet", "shape": {"type": "sphere", "radius": 0.01}, "mass": 0.01,
               "position": [0.05, 0.5, 0.1], "velocity": [0.0, -300.0, 0.0]},
              {"name": "wall", "shape": {"type": "box", "half_extents": [0.5, 0.005, 0.5]},
               "static": True, "position": [0.0, 0.2, 0.5]}]
    return {"integrator": integrator, "gravity": "earth", "bodies": bodies,
            "effects": {"contacts": {"sleep": True, "sleep_time": 0.05},
                        "drag": {"model": "reynolds"},
                        "buoyancy": {"surface_z": 0.15},
                        "gravitation": {}},
            "springs": [{"a": "ball2", "b": "world", "stiffness": 10.0, "damping": 0.1,
                         "point_b": [0.0, 0.0, 1.0]}]}


def warm_up():
    """Step the scenes; returns the seconds it took."""
    t0 = perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        load_scene(default_scene_path()).step(60)
        for integrator in INTEGRATORS:
            world = load_scene(_contact_scene(integrator))
            world.apply_force("crate", [1.0, 0.0, 0.0], point=[0.5, 0.1, 0.2])
            world.apply_impulse("ball", [0.1, 0.0, 0.0], point=[0.0, 0.1, 0.3])
            world.step(40)
            world.add_body({"name": "extra", "shape": {"type": "sphere", "radius": 0.1},
                            "mass": 1.0, "position": [1.0, 0.0, 0.3]})
            world.step(2)
            world.remove_body("ball")
            world.step(2)
    return perf_counter() - t0


def main():
    seconds = warm_up()
    print(f"physics_core: kernels compiled and cached in {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
