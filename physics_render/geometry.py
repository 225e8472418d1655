"""World-space outlines of what is drawn: sphere silhouettes, box faces, a
patch of each plane with its grid, contact normals; and clipping at the
camera's near plane."""

import numpy as np

from .camera import NEAR
from .shapes import rotation_matrix

# Box faces as corner indices (corners numbered by the signs of x, y, z: bit 2
# x, bit 1 y, bit 0 z), wound counter-clockwise seen from outside.
BOX_FACES = ((4, 6, 7, 5), (0, 1, 3, 2), (2, 3, 7, 6), (0, 4, 5, 1), (1, 5, 7, 3), (0, 2, 6, 4))
_CORNER_SIGNS = np.array([[(-1) ** (1 - (c >> 2 & 1)), (-1) ** (1 - (c >> 1 & 1)), (-1) ** (1 - (c & 1))]
                          for c in range(8)], dtype=np.float64)
SILHOUETTE_POINTS = 64


def sphere_silhouette(camera, centre, radius):
    """World points of the circle where the cone from the eye touches the
    sphere: its projection is exactly the sphere's outline on the picture.
    That circle lies a distance r²/d from the centre towards the eye, with
    radius r √(1 − r²/d²) (d = |eye − centre|). None if the eye is inside."""
    centre = np.asarray(centre, dtype=np.float64)
    to_eye = camera.eye - centre
    d = float(np.linalg.norm(to_eye))
    if d <= radius * 1.0001:
        return None
    axis = to_eye / d
    ring_centre = centre + axis * (radius * radius / d)
    ring_radius = radius * np.sqrt(1.0 - (radius / d) ** 2)
    a = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    phi = np.linspace(0.0, 2.0 * np.pi, SILHOUETTE_POINTS, endpoint=False)
    return ring_centre + ring_radius * (np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * b)


def box_faces(pos, quat, half_extents):
    """[(corners (4, 3), outward unit normal (3,))] of a box's six faces, world frame."""
    r = rotation_matrix(quat)
    corners = np.asarray(pos, dtype=np.float64) + (_CORNER_SIGNS * np.asarray(half_extents)) @ r.T
    faces = []
    for axis, sign in ((0, 1), (0, -1), (1, 1), (1, -1), (2, 1), (2, -1)):
        index = BOX_FACES[2 * axis + (sign < 0)]
        faces.append((corners[list(index)], sign * r[:, axis]))
    return faces


def plane_patch(normal, offset, around, half_size):
    """A square of the plane n·x = offset, centred at the foot of `around`,
    and its grid lines: (corners (4, 3), segments (m, 2, 3))."""
    n = np.asarray(normal, dtype=np.float64)
    foot = np.asarray(around, dtype=np.float64) - (n @ around - offset) * n
    a = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    # Grid on round coordinates of the plane's own axes, so it does not slide with the camera.
    spacing = _nice_spacing(half_size / 8.0)
    ca, cb = np.round(foot @ a / spacing) * spacing, np.round(foot @ b / spacing) * spacing
    origin = foot - (foot @ a) * a - (foot @ b) * b + ca * a + cb * b
    signs = ((-1, -1), (1, -1), (1, 1), (-1, 1))
    corners = np.array([origin + sa * half_size * a + sb * half_size * b for sa, sb in signs])
    ticks = np.arange(-half_size, half_size + 0.5 * spacing, spacing)
    segments = [(origin + s * a - half_size * b, origin + s * a + half_size * b) for s in ticks]
    segments += [(origin + s * b - half_size * a, origin + s * b + half_size * a) for s in ticks]
    return corners, np.array(segments)


def _nice_spacing(x):
    """1, 2 or 5 times a power of ten, the nearest at or above x."""
    power = 10.0 ** np.floor(np.log10(x))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * power >= x * 0.999:
            return m * power
    return 10.0 * power


def clip_near(points):
    """Sutherland–Hodgman clip of a camera-space polygon (k, 3) to z >= NEAR."""
    out = []
    k = len(points)
    for i in range(k):
        p, q = points[i], points[(i + 1) % k]
        p_in, q_in = p[2] >= NEAR, q[2] >= NEAR
        if p_in:
            out.append(p)
        if p_in != q_in:
            s = (NEAR - p[2]) / (q[2] - p[2])
            out.append(p + s * (q - p))
    return np.array(out) if len(out) >= 3 else None


def clip_segment_near(p, q):
    """A camera-space segment clipped to z >= NEAR, or None."""
    if p[2] < NEAR and q[2] < NEAR:
        return None
    if p[2] < NEAR:
        p = p + (NEAR - p[2]) / (q[2] - p[2]) * (q - p)
    elif q[2] < NEAR:
        q = q + (NEAR - q[2]) / (p[2] - q[2]) * (p - q)
    return p, q
