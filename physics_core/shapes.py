"""Shape codes, volumes, inertia tensors and drag defaults for sphere, box and plane.

Inertia tensors are principal-axis diagonals in the body frame (the frame
the shape is defined in), so the world tensor is R diag(I) Rᵀ (COURSE.md 3).
"""
import numpy as np

SPHERE, BOX, PLANE = 0, 1, 2
SHAPE_NAMES = {"sphere": SPHERE, "box": BOX, "plane": PLANE}
SHAPE_LABELS = {v: k for k, v in SHAPE_NAMES.items()}

# Drag coefficients of the reference shapes (smooth sphere, cube face-on).
DEFAULT_CD = {SPHERE: 0.47, BOX: 1.05, PLANE: 0.0}


def volume(shape_type, radius, half_extents):
    """Volume (m³) per body; zero for planes."""
    shape_type = np.asarray(shape_type)
    sphere = 4.0 / 3.0 * np.pi * np.asarray(radius) ** 3
    box = 8.0 * np.prod(np.asarray(half_extents), axis=-1)
    return np.where(shape_type == SPHERE, sphere, np.where(shape_type == BOX, box, 0.0))


def principal_inertia(shape_type, mass, radius, half_extents):
    """Body-frame principal moments (n, 3) in kg·m².

    Solid sphere: 2/5 m r². Solid box with half extents (a, b, c):
    m/3 (b² + c²), m/3 (a² + c²), m/3 (a² + b²).
    """
    shape_type = np.asarray(shape_type)
    mass = np.asarray(mass, dtype=float)
    h2 = np.asarray(half_extents, dtype=float) ** 2
    sphere = (0.4 * mass * np.asarray(radius) ** 2)[:, None] * np.ones(3)
    box = mass[:, None] / 3.0 * np.stack(
        [h2[:, 1] + h2[:, 2], h2[:, 0] + h2[:, 2], h2[:, 0] + h2[:, 1]], axis=1)
    out = np.where((shape_type == SPHERE)[:, None], sphere, box)
    return np.where((shape_type == PLANE)[:, None], 0.0, out)


def characteristic_length(shape_type, radius, half_extents):
    """Length used in the Reynolds number: a sphere's diameter; for a box the
    diameter of the sphere of equal volume (so a cube and a sphere of the same
    volume get the same Re)."""
    v = volume(shape_type, radius, half_extents)
    box_d = np.cbrt(6.0 * v / np.pi)
    return np.where(np.asarray(shape_type) == SPHERE, 2.0 * np.asarray(radius), box_d)
