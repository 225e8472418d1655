"""Random scenes as the fields of a Model that collision detection reads
(a plain namespace: no scene file, no World), for the detection tests."""
from types import SimpleNamespace

import numpy as np

from physics_core import quaternion as qt
from physics_core.shapes import BOX, PLANE, SPHERE


def mixed_scene(rng, n, spread, n_planes, big_fraction, static_fraction=0.2):
    """The fields of a Model that detection reads (as test_broadphase.random_scene):
    spheres and boxes, some 20× larger, some static; planes with random normals."""
    kind = rng.choice([SPHERE, BOX], size=n)
    kind[:n_planes] = PLANE
    size = rng.uniform(0.05, 0.5, n) * np.where(rng.random(n) < big_fraction, 20.0, 1.0)
    normal = qt.normalize(rng.normal(size=(n, 3)))
    model = SimpleNamespace(
        n=n, shape_type=kind, radius=size,
        half_extents=np.stack([size * rng.uniform(0.2, 1.0, n) for _ in range(3)], axis=1),
        is_static=(rng.random(n) < static_fraction) | (kind == PLANE),
        plane_normal=normal, plane_offset=rng.uniform(-spread, 0.0, n))
    return model, rng.uniform(-spread, spread, (n, 3)), qt.normalize(rng.normal(size=(n, 4)))


def jiggled(pos, quat, static, rng, shift, turn):
    """Poses moved and turned a little (static bodies stay)."""
    move = ~static[:, None]
    pos = pos + rng.normal(0.0, shift, pos.shape) * move
    spin = qt.from_rotation_vector(rng.normal(0.0, turn, pos.shape) * move)
    return pos, qt.normalize(qt.multiply(spin, quat))
