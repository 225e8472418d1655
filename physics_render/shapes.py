"""What each body looks like: shape, size, colour; from a scene's Model or
from the `~/bodies` MarkerArray a recording holds.

Shape codes are the engine's (physics_core.shapes): 0 sphere, 1 box, 2 plane.
"""

from dataclasses import dataclass

import numpy as np

from physics_core.shapes import BOX, PLANE, SPHERE

# Dynamic bodies take these colours in scene order; static ones are grey.
PALETTE = (
    (0.86, 0.33, 0.26),
    (0.22, 0.50, 0.82),
    (0.96, 0.66, 0.18),
    (0.35, 0.68, 0.38),
    (0.58, 0.42, 0.76),
    (0.16, 0.70, 0.72),
    (0.80, 0.45, 0.62),
)
STATIC_RGB = (0.62, 0.63, 0.65)
# The node draws a plane as a CUBE marker this thin (msg_adapters.markers):
# a cube marker at most this thick and this wide is read back as a plane.
_PLANE_MARKER_THICKNESS = 0.0021
_PLANE_MARKER_WIDTH = 10.0


@dataclass(frozen=True)
class Shapes:
    names: tuple
    kind: np.ndarray  # (n,) SPHERE, BOX or PLANE
    radius: np.ndarray  # (n,) m (spheres)
    half_extents: np.ndarray  # (n, 3) m (boxes)
    plane_normal: np.ndarray  # (n, 3) unit (planes): the half-space n·x <= offset is solid
    plane_offset: np.ndarray  # (n,) m
    static: np.ndarray  # (n,) bool
    # Springs as (a, b, point_a, point_b): body index (-1 = the world) and the
    # attachment in that body's frame (world frame for the world).
    springs: tuple = ()

    def __len__(self):
        return len(self.names)

    def color(self, i):
        if self.static[i]:
            return STATIC_RGB
        return PALETTE[i % len(PALETTE)]

    def bounding_radius(self, i):
        """Radius of a sphere around body i's centre that holds the body (0 for a plane)."""
        if self.kind[i] == SPHERE:
            return float(self.radius[i])
        if self.kind[i] == BOX:
            return float(np.linalg.norm(self.half_extents[i]))
        return 0.0

    @classmethod
    def from_model(cls, model):
        normal = np.asarray(model.plane_normal, dtype=np.float64).reshape(-1, 3)
        norms = np.linalg.norm(normal, axis=1)
        normal = np.where(norms[:, None] > 0, normal / np.where(norms > 0, norms, 1.0)[:, None], normal)
        return cls(
            names=tuple(model.names),
            kind=np.asarray(model.shape_type, dtype=np.int64).copy(),
            radius=np.asarray(model.radius, dtype=np.float64).copy(),
            half_extents=np.asarray(model.half_extents, dtype=np.float64).reshape(-1, 3).copy(),
            plane_normal=normal,
            plane_offset=np.asarray(model.plane_offset, dtype=np.float64).copy(),
            static=np.asarray(model.is_static, dtype=bool).copy(),
            springs=tuple(
                (int(a), int(b), np.array(pa, dtype=np.float64), np.array(pb, dtype=np.float64))
                for a, b, pa, pb in zip(model.springs.a, model.springs.b, model.springs.point_a, model.springs.point_b)
            ),
        )

    @classmethod
    def from_markers(cls, markers):
        """From the node's `~/bodies` MarkerArray (one marker per body, id =
        scene index): SPHERE markers are spheres, CUBE markers boxes, and the
        thin wide slab the node draws for a plane is a plane again. A body is
        taken as static when its colour is the node's static grey. Markers
        do not carry springs."""
        rows = sorted((m for m in markers.markers if m.action == 0), key=lambda m: m.id)
        rows = [_marker_row(m) for m in rows]
        if not rows:
            raise ValueError("the bodies marker array is empty")
        names, kind, radius, half, normal, offset, static = zip(*rows)
        return cls(
            names=tuple(names),
            kind=np.array(kind, dtype=np.int64),
            radius=np.array(radius, dtype=np.float64),
            half_extents=np.array(half, dtype=np.float64),
            plane_normal=np.array(normal, dtype=np.float64),
            plane_offset=np.array(offset, dtype=np.float64),
            static=np.array(static, dtype=bool),
        )


def _marker_row(m):
    """(name, kind, radius, half extents, plane normal, plane offset, static) of one marker."""
    SPHERE_MARKER, CUBE_MARKER = 2, 1  # visualization_msgs/Marker type codes
    grey = abs(m.color.r - m.color.g) < 1e-6 and abs(m.color.g - m.color.b) < 1e-6
    name = m.ns or m.text or f"body{m.id}"
    zero3 = (0.0, 0.0, 0.0)
    if m.type == SPHERE_MARKER:
        return name, SPHERE, 0.5 * m.scale.x, zero3, zero3, 0.0, grey
    if m.type != CUBE_MARKER:
        raise ValueError(f"body marker {m.id} ({name}) has marker type {m.type}, not a sphere or a cube")
    size = (m.scale.x, m.scale.y, m.scale.z)
    if m.scale.z <= _PLANE_MARKER_THICKNESS and min(m.scale.x, m.scale.y) >= _PLANE_MARKER_WIDTH:
        o = m.pose.orientation
        n = rotation_matrix(np.array([o.w, o.x, o.y, o.z]))[:, 2]
        top = np.array([m.pose.position.x, m.pose.position.y, m.pose.position.z]) + 0.5 * m.scale.z * n
        return name, PLANE, 0.0, zero3, tuple(n.tolist()), float(n @ top), True
    return name, BOX, 0.0, tuple(0.5 * s for s in size), zero3, 0.0, grey


def rotation_matrix(q):
    """Rotation matrix of a unit quaternion (w, x, y, z): body axes as its columns."""
    w, x, y, z = (float(c) for c in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
