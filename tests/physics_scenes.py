"""Scene dicts shared by the physics-core tests (and mirrored by benchmarks/core_speed.py).

Each helper returns a plain dict in the scene format of INTERFACE.md, so a
test states the physical set-up in one line and reads like the experiment.
"""
import hashlib
import math

import numpy as np

# The course's constants and planets (COURSE.md 2), restated here on purpose so
# the tests check planets.py rather than reuse it.
G_COURSE = 6.673e-11
PLANET_DATA = {
    "earth": (5.98e24, 6.377e6),
    "moon": (7.35e22, 1.738e6),
    "mars": (6.42e23, 3.403e6),
}
INTEGRATORS = ("explicit_euler", "semi_implicit_euler", "velocity_verlet", "rk4")


def g_of(planet, altitude=0.0):
    """g = G m / (r + h)² (COURSE.md 2)."""
    m, r = PLANET_DATA[planet]
    return G_COURSE * m / (r + altitude) ** 2


def sphere(name="ball", radius=0.1, mass=1.0, position=(0.0, 0.0, 0.0), **extra):
    """A sphere; pass mass=None with density=... to size the mass from the volume."""
    body = {"name": name, "shape": {"type": "sphere", "radius": radius},
            "position": [float(x) for x in position]}
    if mass is not None:
        body["mass"] = mass
    body.update(extra)
    return body


def box(name="box", half_extents=(0.5, 0.3, 0.1), mass=1.0, position=(0.0, 0.0, 0.0), **extra):
    body = {"name": name, "shape": {"type": "box", "half_extents": [float(x) for x in half_extents]},
            "position": [float(x) for x in position]}
    if "density" not in extra:
        body["mass"] = mass
    body.update(extra)
    return body


def scene(*bodies, dt=1.0 / 240.0, integrator="semi_implicit_euler", **top):
    out = {"dt": dt, "integrator": integrator, "bodies": list(bodies)}
    out.update(top)
    return out


def oscillator(k, m, x0=1.0, damping=0.0, integrator="rk4", dt=1.0 / 240.0, v0=0.0):
    """A point-like sphere on a spring to a fixed world point at the origin, rest length 0.

    Motion stays on the x axis: x'' = -(k/m) x - (c/m) x'."""
    return scene(sphere("bob", radius=0.01, mass=m, position=(x0, 0.0, 0.0),
                        velocity=[float(v0), 0.0, 0.0]),
                 springs=[{"a": "bob", "b": "world", "stiffness": float(k), "rest_length": 0.0,
                           "damping": float(damping), "point_b": [0.0, 0.0, 0.0]}],
                 integrator=integrator, dt=dt)


def axis_angle(axis, angle):
    """Unit quaternion [w, x, y, z] for a rotation of `angle` rad about `axis`."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    return [math.cos(angle / 2)] + [float(x) for x in a * math.sin(angle / 2)]


def rotation_matrix(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def state_hash(world) -> str:
    """SHA-256 of every state array's bytes: equal hashes mean bit-identical states."""
    s = world.state
    h = hashlib.sha256()
    for a in (s.pos, s.quat, s.vel, s.omega):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr(s.time).encode())
    return h.hexdigest()


def slope(xs, ys):
    """Least-squares slope of log(ys) against log(xs): the observed order of a method."""
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])
